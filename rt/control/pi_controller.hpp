// The PI law of seed 000 (eq. 9-10), written as a true discrete integrator
// (the paper's u = Kp e + Ki e Ts has none; docs/rig-models.md 1.5.5),
// with an optional velocity feedforward of the demand:
//   e_k = r_k - y_k,  I_k = I_{k-1} + Ki Ts e_k,
//   u_k = sat(Kp e_k + I_k + Kff (r_k - r_{k-1}) / Ts)
// A valve-controlled cylinder is an integrator (flow -> velocity), so a PI
// alone lags a moving demand by the rod's speed over ki; the feedforward
// opens the valve for the demanded speed directly (Kff = 1 / the plant's
// velocity gain, `rigctl tune` measures it) and leaves the feedback only
// the model's error. It does not change the loop's margins (it acts outside
// the loop). The first tick after reset() has no previous demand: no
// feedforward, so a run starts without a kick.
// The integrator is held (I_k = I_{k-1}) by the anti-windup below and on a
// tick whose sample says the output's actuator is not following
// (Sample::outputs_not_following).
#pragma once

#include "rt/control/controller.hpp"

namespace rigctl {

// Anti-windup strategy.
enum class AntiWindup {
  // Conditional integration (clamping): the integrator is held on a tick
  // where the output is saturated and the error would drive it further into
  // saturation. Simple, no extra tuning parameter, and the integrator resumes
  // the moment the error changes sign, so the loop leaves saturation without
  // the overshoot of a wound-up integrator.
  kConditional,
  // Plain integration; only for comparison in tests.
  kNone,
};

struct PiConfig {
  double kp = 80.0;            // [1/m]: output per metre of error
  double ki = 60.0;            // [1/(m s)]
  // [s/m]: output per m/s of demand rate; 0 = none. Meant for a filtered
  // demand: an unfiltered step is one tick at full valve.
  double velocity_feedforward = 0.0;
  double period_s = 0.0025;    // Ts [s]
  double output_limit = 1.0;   // |u| <= limit (fraction of rated valve current)
  AntiWindup anti_windup = AntiWindup::kConditional;
  int feedback_input = 0;      // index of the measured channel in the sample
  int output_index = 0;        // index of the command output
};

class PiController final : public Controller {
 public:
  explicit PiController(const PiConfig& config);
  const std::string& name() const override { return name_; }
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override {
    integrator_ = 0.0;
    has_previous_setpoint_ = false;
  }
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

  double integrator() const noexcept { return integrator_; }

 private:
  PiConfig config_;
  std::string name_ = "pi";
  std::vector<std::string> term_names_{"p", "i"};  // and "ff" when the feedforward is on
  double integrator_ = 0.0;
  double previous_setpoint_ = 0.0;
  bool has_previous_setpoint_ = false;
};

}  // namespace rigctl
