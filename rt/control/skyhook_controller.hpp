// Skyhook active suspension (Karnopp): a damper from each body corner to an
// inertial reference, F_i = -c_sky (z_s_dot + l_i phi_dot), clamped to
// +-force_limit. Acts in parallel with the passive damper. A baseline for
// the fuzzy controller of seed 001.
#pragma once

#include "rt/control/suspension_controller.hpp"

namespace rigctl {

struct SkyhookConfig {
  // [N s/m] per corner. Chosen: about 0.4 of the critical damping of the
  // front corner's body mode (2 sqrt(k_eff m_corner) with k_eff = 57 kN/m,
  // spring and tyre in series, and 490 kg of body at the front corner:
  // 10.6 kN s/m), a common skyhook level; not tuned to a result.
  double c_sky = 4000.0;
  double force_limit = kDefaultSuspensionForceLimit;  // [N]
  LeverArms lever_arm = kPitchLeverArms;
  SuspensionChannels channels;
};

class SkyhookController final : public Controller {
 public:
  explicit SkyhookController(const SkyhookConfig& config);
  const std::string& name() const override { return name_; }
  // "f_1", "f_2": clamped forces; "v_1", "v_2": body corner velocities.
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override {}
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

 private:
  SkyhookConfig config_;
  std::string name_ = "skyhook";
  std::vector<std::string> term_names_{"f_1", "f_2", "v_1", "v_2"};
};

}  // namespace rigctl
