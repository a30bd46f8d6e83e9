// Stepping the quarter-car plant in open loop for its unit tests, and the
// hand calculations several of them check against (suspension force,
// breakaway force, a state held by the bearing), written out from
// docs/rig-models.md section 1 independently of the plant's code.
#pragma once

#include <array>
#include <cmath>

#include "plant/quarter_car/quarter_car_plant.hpp"

namespace rigctl::quarter_car_test {

namespace sig = quarter_car_signal;

constexpr double kDt = 0.0025;  // control period the plant is stepped at [s]
constexpr double kBar = 1e5;

inline double total_mass(const QuarterCarParams& p) { return p.mass_rod + p.mass_wheel + p.mass_body; }

// Advances with u held and calls f(time, plant) after every period.
template <typename F>
void run(QuarterCarPlant& plant, double u, double seconds, F&& f, double t0 = 0.0) {
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int i = 1; i <= n; ++i) {
    plant.advance({&u, 1}, kDt);
    f(t0 + i * kDt, plant);
  }
}
inline void run(QuarterCarPlant& plant, double u, double seconds) {
  run(plant, u, seconds, [](double, const QuarterCarPlant&) {});
}

inline std::array<double, sig::kCount> measured(const QuarterCarPlant& plant) {
  std::array<double, sig::kCount> out{};
  plant.measure(out);
  return out;
}

inline double suspension_force(const QuarterCarParams& p, const QuarterCarState& s) {
  return p.spring_stiffness * (s.x_w - s.x_b) + p.damper_damping * (s.v_w - s.v_b);
}

// Breakaway force written out from docs/rig-models.md 1.5.4 and seed eq. 14,
// independently of plant/quarter_car/bearing_friction.cpp.
inline double breakaway(const QuarterCarParams& p, const QuarterCarState& s) {
  const auto& f = p.bearing_friction;
  const double dx = s.x_w - s.x_b;
  const double dtheta = std::asin(dx * std::sin(f.construction_angle) /
                                  (f.damper_free_length - dx * std::sin(f.construction_angle)));
  const double normal =
      std::abs(p.mass_body * p.gravity + suspension_force(p, s)) / std::tan(f.construction_angle - dtheta);
  return f.coulomb_base + f.normal_coefficient * normal + f.stiction_excess;
}

// State with everything at rest under a constant suspension force `f_susp`
// held by the bearing, the valve closed and no leakage: the rod is then held
// by the trapped oil alone.
inline QuarterCarState held_state(const QuarterCarParams& p, double f_susp) {
  QuarterCarState s;
  s.x_r = 0.0;
  s.x_w = s.x_r - f_susp / p.tyre_stiffness;  // wheel: kt (x_r - x_w) = F_susp
  s.x_b = s.x_w - f_susp / p.spring_stiffness;
  s.p1 = s.p2 = (total_mass(p) * p.gravity + f_susp) / (p.area_cap - p.area_rod);
  s.bearing = BearingMode::kStuck;
  return s;
}

inline QuarterCarParams closed_valve_params(bool friction) {
  QuarterCarParams p;
  p.leakage = false;
  p.bearing_friction.enabled = friction;
  return p;
}

}  // namespace rigctl::quarter_car_test
