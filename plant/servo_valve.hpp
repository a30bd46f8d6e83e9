// Flow law of the quarter-car rig's four-way servovalve (seed 000 eqs. 2-5,
// flow gain and laminar branch per docs/rig-models.md 1.5.1).
#pragma once

namespace rigctl {

// sign(p) sqrt|p|, replaced below `laminar_pressure` by p / sqrt(laminar_pressure):
// the square root's infinite slope at p = 0 would make dP/dt non-Lipschitz
// and stiffen the pressure equations without bound near a balanced port.
// Continuous at |p| = laminar_pressure.
double orifice_root(double p, double laminar_pressure);

struct ValveFlows {
  double q1 = 0.0;  // into the cap-side chamber (side 1) [m^3/s]
  double q2 = 0.0;  // out of the rod-side chamber (side 2) [m^3/s]
};

// Critically lapped spool at `spool` (fraction of rated, + extends): for
// spool >= 0 side 1 is fed from supply and side 2 drains to tank; for
// spool < 0 the roles swap, and both flows come out negative.
ValveFlows valve_flows(double spool, double p1, double p2, double flow_gain,
                       double supply_pressure, double laminar_pressure);

// Spool opening of an overlapped spool (any unit of travel): sharp (no
// metering inside +-overlap) when edge_radius is 0, else rounded metering
// edges, a quadratic blend over +-edge_radius about the overlap
// (C1-continuous). overlap <= 0: the critically lapped spool, x itself.
double overlapped_spool(double x, double overlap, double edge_radius);

}  // namespace rigctl
