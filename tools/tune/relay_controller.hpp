// The controller of a relay experiment (Astrom and Hagglund): first a
// proportional stabiliser holds the operating point and learns the command
// that holds it, then a relay with hysteresis about that command drives the
// loop into its limit cycle. The relay's output is clamped to the valve's
// range; whenever the oscillation grows beyond the amplitude clamp the relay
// halves its output (an amplitude clamp: the cycle shrinks instead of
// running into a limit). Allocation-free, as every controller on the loop.
#pragma once

#include <cstdint>

#include "rt/control/controller.hpp"

namespace rigctl {

struct RelaySettings {
  double stabiliser_gain = 1.0;  // P gain of the holding phase
  int64_t hold_ticks = 800;      // ticks of holding before the relay starts
  int64_t learn_ticks = 400;     // the last ticks of holding whose mean command is the hold command
  double amplitude = 0.1;        // relay output about the hold command
  double hysteresis = 1e-4;      // [feedback unit] the relay switches at e = +-hysteresis
  double amplitude_clamp = 1.0;  // [feedback unit] |e| beyond it halves the relay output
  double output_limit = 1.0;
  int feedback_input = 0;
  int output_index = 0;
};

class RelayController final : public Controller {
 public:
  explicit RelayController(const RelaySettings& settings);
  const std::string& name() const override { return name_; }
  // "relay": +1/-1 while relaying, 0 while holding; "hold": the hold command; "d": the relay output
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override;
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

  double hold_command() const noexcept { return hold_; }
  double relay_amplitude() const noexcept { return d_; }
  int halvings() const noexcept { return halvings_; }

 private:
  RelaySettings s_;
  std::string name_ = "relay";
  std::vector<std::string> term_names_{"relay", "hold", "d"};
  int64_t tick_ = 0;
  double sum_ = 0.0;
  double hold_ = 0.0;
  double d_ = 0.0;
  int state_ = 1;
  bool beyond_clamp_ = false;
  int halvings_ = 0;
};

}  // namespace rigctl
