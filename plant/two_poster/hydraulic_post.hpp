// One post of a road simulator: the quarter car's servovalve and asymmetric
// cylinder (seed 000; docs/rig-models.md 1.2 and 1.5), its platen carrying
// a wheel. Spool first order behind the command, the four-way valve's
// orifice flows, both chambers compressible (with entrained air when asked)
// and joined by cross-port leakage (laminar, with an optional worn-seal
// orifice), seal friction on the rod, end stops. Pressures gauge, SI units.
// A pure function of state and input: the plant that owns the posts
// integrates it.
#pragma once

#include <array>

namespace rigctl {

struct HydraulicPostParams {
  // The quarter car's actuator (plant/quarter_car/quarter_car_params.hpp:
  // its sources are there).
  double area_cap = 1.96e-3;        // A1 [m^2]
  double area_rod = 0.94e-3;        // A2 [m^2]
  double bulk_modulus = 1.43e9;     // beta [Pa]
  double supply_pressure = 200e5;   // Ps [Pa gauge]
  double valve_flow_gain = 1.782e-7;   // [m^3/s/sqrt(Pa)] at full spool
  double valve_time_constant = 0.004;  // [s]
  double laminar_pressure = 2e5;       // [Pa]
  double cavitation_pressure = -0.95e5;  // [Pa gauge]
  double leakage_resistance = 2.45e11;   // R_l [Pa s/m^3]
  double dead_volume = 30e-6;            // each chamber's [m^3]
  double stroke_min = -0.010, stroke_max = 0.170;  // [m], 0 = home
  double end_stop_stiffness = 5e7;       // [N/m]
  double end_stop_damping = 2e4;         // [N s/m]
  double mass_platen = 5.0;              // rod and platen [kg]
  double rod_damping = 500.0;            // [N s/m]
  // Hidden effects (0: none), the forms the quarter car's generator uses.
  double extra_laminar_leak = 0.0;       // [m^3/s/Pa] added cross-port conductance: seal wear
  double worn_seal_orifice = 0.0;        // [m^3/s/sqrt(Pa)] turbulent cross-port leak
  double seal_friction = 0.0;            // [N] Coulomb level of the rod seal, smoothed over seal_velocity
  double seal_velocity = 0.005;          // [m/s] tanh width of the seal's Coulomb law
  double air_fraction = 0.0;             // free air at atmosphere [1], isothermal bubbles
};

// x_s, p1, p2, x_r, v_r.
using PostState = std::array<double, 5>;
namespace post {
inline constexpr std::size_t kXs = 0, kP1 = 1, kP2 = 2, kXr = 3, kVr = 4;
}

// d/dt of the post under command u (held) with `load` pushing the platen
// down [N] (the wheel's tyre force and the platen's weight).
PostState post_derivatives(const HydraulicPostParams& p, const PostState& y, double u, double load);

// At rest at home carrying `load` [N]: pressures with P1 A1 - P2 A2 = load
// and, with leakage, the spool where the valve meters the leak flow.
PostState post_rest(const HydraulicPostParams& p, double load);

// The cavitation floor of both chambers (after each integration step).
void post_floors(const HydraulicPostParams& p, PostState& y);

}  // namespace rigctl
