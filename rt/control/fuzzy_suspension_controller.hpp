// The fuzzy active suspension of seed 001: one Mamdani engine (the paper's
// membership functions and 27-rule table by default, any FuzzyEngineSpec
// from config otherwise) applied at each body corner, as the paper runs one
// controller per actuator.
//
// Inputs at corner i, in the error convention of a regulator (demand minus
// measurement, so that the table's positive output opposes a negative
// deviation):
//   x1_i = 0 - (z_s_dot + l_i phi_dot)   body corner velocity error (the
//          paper's text: "the input ... is the speed and acceleration of the
//          vehicle body"), or, with FuzzyFirstInput::kDisplacement,
//          x1_i = setpoint - (z_s + l_i phi) (the table's theta symbol);
//   x2_i = 0 - (z_s_ddot + l_i phi_ddot)  body corner acceleration error.
// Output: f_i = engine(x1_i, x2_i) [N] (the engine's output scale maps the
// universe to force), clamped to +-force_limit.
#pragma once

#include <array>

#include "rt/control/fuzzy_engine.hpp"
#include "rt/control/suspension_controller.hpp"

namespace rigctl {

enum class FuzzyFirstInput { kVelocity, kDisplacement };

struct FuzzySuspensionConfig {
  FuzzyEngineSpec engine = paper_fuzzy_spec();
  FuzzyFirstInput first_input = FuzzyFirstInput::kVelocity;
  double force_limit = kDefaultSuspensionForceLimit;  // [N] per actuator
  LeverArms lever_arm = kPitchLeverArms;
  SuspensionChannels channels;
};

class FuzzySuspensionController final : public Controller {
 public:
  // Throws std::invalid_argument for an engine that does not take exactly
  // two inputs or a non-positive force limit.
  explicit FuzzySuspensionController(const FuzzySuspensionConfig& config);
  const std::string& name() const override { return name_; }
  // "f_1", "f_2": clamped forces; "x1_1", "x2_1", "x1_2", "x2_2": the
  // engine inputs at each corner (physical units).
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override {}
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

  const FuzzyEngine& engine() const { return engine_; }

 private:
  FuzzySuspensionConfig config_;
  FuzzyEngine engine_;
  std::string name_ = "fuzzy";
  std::vector<std::string> term_names_{"f_1", "f_2", "x1_1", "x2_1", "x1_2", "x2_2"};
};

}  // namespace rigctl
