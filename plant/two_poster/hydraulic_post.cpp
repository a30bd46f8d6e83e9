#include "plant/two_poster/hydraulic_post.hpp"

#include <algorithm>
#include <cmath>

#include "plant/servo_valve.hpp"

namespace rigctl {

namespace {

using namespace post;

constexpr double kMinVolume = 1e-7;      // [m^3] keeps a chamber finite past the end stop
constexpr double kAtmosphere = 1.013e5;  // [Pa absolute]

// Effective bulk modulus of oil with free air (isothermal bubbles, the
// mixture law: the air's share of the compliance grows as the pressure falls).
double bulk_modulus(const HydraulicPostParams& p, double gauge) {
  if (p.air_fraction <= 0.0) return p.bulk_modulus;
  const double absolute = std::max(gauge + kAtmosphere, 1e4);
  const double air = p.air_fraction * kAtmosphere / absolute;  // volume share at this pressure
  return 1.0 / ((1.0 - air) / p.bulk_modulus + air / absolute);
}

double cross_port_leak(const HydraulicPostParams& p, double dp) {
  double q = dp / p.leakage_resistance + p.extra_laminar_leak * dp;
  if (p.worn_seal_orifice > 0.0) q += p.worn_seal_orifice * orifice_root(dp, p.laminar_pressure);
  return q;
}

double end_stop(const HydraulicPostParams& p, double x, double v) {
  if (x < p.stroke_min) return -p.end_stop_stiffness * (x - p.stroke_min) - p.end_stop_damping * v;
  if (x > p.stroke_max) return -p.end_stop_stiffness * (x - p.stroke_max) - p.end_stop_damping * v;
  return 0.0;
}

}  // namespace

PostState post_derivatives(const HydraulicPostParams& p, const PostState& y, double u, double load) {
  PostState dy{};
  dy[kXs] = (u - y[kXs]) / p.valve_time_constant;
  const ValveFlows q = valve_flows(y[kXs], y[kP1], y[kP2], p.valve_flow_gain, p.supply_pressure, p.laminar_pressure);
  const double leak = cross_port_leak(p, y[kP1] - y[kP2]);
  const double v1 = std::max(p.dead_volume + p.area_cap * (y[kXr] - p.stroke_min), kMinVolume);
  const double v2 = std::max(p.dead_volume + p.area_rod * (p.stroke_max - y[kXr]), kMinVolume);
  double dp1 = bulk_modulus(p, y[kP1]) / v1 * (q.q1 - p.area_cap * y[kVr] - leak);
  double dp2 = bulk_modulus(p, y[kP2]) / v2 * (p.area_rod * y[kVr] + leak - q.q2);
  if (y[kP1] <= p.cavitation_pressure && dp1 < 0.0) dp1 = 0.0;
  if (y[kP2] <= p.cavitation_pressure && dp2 < 0.0) dp2 = 0.0;
  dy[kP1] = dp1;
  dy[kP2] = dp2;
  const double seal = p.seal_friction > 0.0 ? p.seal_friction * std::tanh(y[kVr] / p.seal_velocity) : 0.0;
  dy[kXr] = y[kVr];
  dy[kVr] = (y[kP1] * p.area_cap - y[kP2] * p.area_rod - p.rod_damping * y[kVr] - seal - load +
             end_stop(p, y[kXr], y[kVr])) / p.mass_platen;
  return dy;
}

PostState post_rest(const HydraulicPostParams& p, double load) {
  PostState s{};
  // P1 + P2 = Ps: the valve then meters the leak in through one edge and
  // out through the other at one spool position (as the quarter car's rest).
  s[kP1] = (load + p.supply_pressure * p.area_rod) / (p.area_cap + p.area_rod);
  s[kP2] = p.supply_pressure - s[kP1];
  const double leak = cross_port_leak(p, s[kP1] - s[kP2]);
  const double root = orifice_root(leak >= 0.0 ? s[kP2] : s[kP1], p.laminar_pressure);
  s[kXs] = root != 0.0 ? leak / (p.valve_flow_gain * root) : 0.0;
  return s;
}

void post_floors(const HydraulicPostParams& p, PostState& y) {
  y[kP1] = std::max(y[kP1], p.cavitation_pressure);
  y[kP2] = std::max(y[kP2], p.cavitation_pressure);
}

}  // namespace rigctl
