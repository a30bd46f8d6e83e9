#include "tools/tune/relay_controller.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

RelayController::RelayController(const RelaySettings& s) : s_(s) { reset(); }

void RelayController::reset() noexcept {
  tick_ = 0;
  sum_ = hold_ = 0.0;
  d_ = s_.amplitude;
  state_ = 1;
  beyond_clamp_ = false;
  halvings_ = 0;
}

void RelayController::update(double setpoint, const Sample& sample, Command& command,
                             ControllerTerms& terms) noexcept {
  const double y = sample.value[static_cast<std::size_t>(s_.feedback_input)];
  const double e = setpoint - y;
  double u = 0.0;
  if (tick_ < s_.hold_ticks) {
    u = s_.stabiliser_gain * e;
    if (tick_ >= s_.hold_ticks - s_.learn_ticks) sum_ += u;
    if (tick_ == s_.hold_ticks - 1) {
      hold_ = sum_ / static_cast<double>(s_.learn_ticks);
      // The relay must fit in the valve's range on both sides of the hold.
      d_ = std::min(d_, s_.output_limit - std::abs(hold_));
    }
    terms.term[0] = 0.0;
  } else {
    if (e > s_.hysteresis) state_ = 1;
    if (e < -s_.hysteresis) state_ = -1;
    const bool beyond = std::abs(e) > s_.amplitude_clamp;
    if (beyond && !beyond_clamp_) {
      d_ *= 0.5;
      ++halvings_;
    }
    beyond_clamp_ = beyond;
    u = hold_ + d_ * state_;
    terms.term[0] = state_;
  }
  ++tick_;
  const double output = std::clamp(u, -s_.output_limit, s_.output_limit);
  command.value[static_cast<std::size_t>(s_.output_index)] = output;
  terms.term[1] = hold_;
  terms.term[2] = d_;
  fill_terms(terms, {.setpoint = setpoint, .measurement = y, .unsaturated = u, .output = output, .saturated = u != output});
}

}  // namespace rigctl
