// The gains `rigctl tune` designs, for the rigs' position controllers: PI
// (the quarter car) and P+V+dP (the pneumatic servo), with the fixed parts
// of each controller that shape its frequency response.
#pragma once

#include <map>
#include <string>

#include "config/rig_config.hpp"

namespace rigctl {

struct LoopGains {
  ControllerKind kind = ControllerKind::kPi;
  double period_s = 0.0025;
  double output_limit = 1.0;
  // PI: u = kp e + ki sum(e) Ts + kff dr/dt (the feedforward is outside the
  // loop: it changes the step, not the margins)
  double kp = 0.0, ki = 0.0, kff = 0.0;
  // P+V+dP: u = Ke e - Kp dp - Kv omega (Kp in V/Pa here, V/bar in the config)
  double ke = 0.0, kv = 0.0, kp_pressure = 0.0;
  bool transient_pressure = false;
  double transient_tau_s = 1.0;
  double velocity_filter_tau_s = 0.01;

  static LoopGains from_config(const RigConfig& config);
  LoopGains with_ke(double value) const {
    LoopGains g = *this;
    g.ke = value;
    return g;
  }
  // The controller section's gain keys and values in the config's units
  // (kp_v_per_bar in V/bar): what a tuned config changes.
  std::map<std::string, double> config_values() const;
  // The gains applied to a controller config (the loop that runs them).
  void apply_to(ControllerConfig& controller) const;
};

}  // namespace rigctl
