// Stepping the rotary pneumatic plant in open loop for its unit tests: the
// control period, the linear plant alone, a held command for a while.
#pragma once

#include <array>
#include <cmath>

#include "plant/pneumatic_rotary/pneumatic_rotary_plant.hpp"

namespace rigctl::pneumatic_test {

namespace sig = pneumatic_rotary_signal;

constexpr double kDt = 0.0025;  // control period [s]
// The linear plant alone: no dither, no hysteresis, no brake.
inline PneumaticRotaryParams bare_params() {
  PneumaticRotaryParams p;
  p.dither = false;
  p.hysteresis.enabled = false;
  p.brake.enabled = false;
  return p;
}

inline std::array<double, sig::kCount> measured(const PneumaticRotaryPlant& plant) {
  std::array<double, sig::kCount> out{};
  plant.measure(out);
  return out;
}

// Advances with u held for `seconds` in steps of dt and calls f(t, plant)
// after each step.
template <typename F>
void run(PneumaticRotaryPlant& plant, double u, double seconds, F&& f, double dt = kDt) {
  const int n = static_cast<int>(std::lround(seconds / dt));
  const double t0 = plant.state().time;
  for (int i = 1; i <= n; ++i) {
    plant.advance({&u, 1}, dt);
    f(t0 + i * dt, plant);
  }
}
inline void run(PneumaticRotaryPlant& plant, double u, double seconds) {
  run(plant, u, seconds, [](double, const PneumaticRotaryPlant&) {});
}

}  // namespace rigctl::pneumatic_test
