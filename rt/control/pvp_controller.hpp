// The pneumatic servo's controller of seed 002, eq. 1 with the sign
// convention of docs/rig-models.md 2.6.1 (every term negative
// feedback, valve opening +U drives theta up):
//   U = Ke (theta_d - theta) - Kp dp - Kv omega,   saturated at +-U_max
// With transient pressure feedback (eq. 18) the pressure term acts on the
// high-passed pressure, tau_f s / (1 + tau_f s), so it vanishes at rest and
// leaves no steady-state error against hysteresis. omega is the filtered
// difference of the measured angle (the rig has no tachometer in the loop).
#pragma once

#include "rt/control/controller.hpp"

namespace rigctl {

struct PvpConfig {
  double ke = 3.7;        // [V/rad]
  double kv = 0.0;        // [V/(rad/s)]
  double kp = 0.0;        // [V/Pa] on the differential pressure
  bool transient_pressure = false;  // Kp acts on the high-passed pressure (eq. 18)
  double tau_f = 1.0;     // [s] high-pass time constant of eq. 18
  double velocity_filter_tau = 0.01;  // [s] first-order filter on the angle difference
  double output_limit = 5.0;  // [V]
  double period_s = 0.0025;
  int angle_input = 0;     // theta
  int pressure_input = 1;  // dp = P_a - P_b
  int output_index = 0;
};

class PvpController final : public Controller {
 public:
  explicit PvpController(const PvpConfig& config);
  const std::string& name() const override { return name_; }
  // "e": Ke error part, "p": pressure part, "v": velocity part, "omega": velocity estimate
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override;
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

 private:
  PvpConfig config_;
  std::string name_ = "pvp";
  std::vector<std::string> term_names_{"e", "p", "v", "omega"};
  double velocity_alpha_;  // filter weight per tick
  double highpass_a_;      // discrete high-pass coefficient
  bool primed_ = false;
  double last_angle_ = 0.0;
  double omega_ = 0.0;
  double last_pressure_ = 0.0;
  double transient_ = 0.0;
};

}  // namespace rigctl
