#include "rt/control/pi_controller.hpp"

#include <algorithm>
#include <stdexcept>

namespace rigctl {

PiController::PiController(const PiConfig& config) : config_(config) {
  if (config.period_s <= 0.0) throw std::invalid_argument("PI period must be positive");
  if (config.output_limit <= 0.0) throw std::invalid_argument("PI output limit must be positive");
  if (config.velocity_feedforward < 0.0) throw std::invalid_argument("PI velocity feedforward must not be negative");
  if (config.velocity_feedforward > 0.0) term_names_.push_back("ff");
}

void PiController::update(double setpoint, const Sample& sample, Command& command,
                          ControllerTerms& terms) noexcept {
  const double measurement = sample.value[static_cast<std::size_t>(config_.feedback_input)];
  const double error = setpoint - measurement;
  const double limit = config_.output_limit;

  const double p = config_.kp * error;
  const double ff = has_previous_setpoint_
                        ? config_.velocity_feedforward * (setpoint - previous_setpoint_) / config_.period_s
                        : 0.0;
  previous_setpoint_ = setpoint;
  has_previous_setpoint_ = true;
  const double candidate = integrator_ + config_.ki * config_.period_s * error;
  const double unsat_with_candidate = p + ff + candidate;
  // The valve is not following (the driver says so): the error does not
  // answer the command, and integrating it would wind up whatever the valve
  // takes once it follows again.
  const bool not_following = ((sample.outputs_not_following >> config_.output_index) & 1U) != 0;
  bool held = false;
  if (not_following) {
    held = true;
  } else if (config_.anti_windup == AntiWindup::kConditional &&
             ((unsat_with_candidate > limit && error > 0.0) || (unsat_with_candidate < -limit && error < 0.0))) {
    held = true;  // integrating would only push further into saturation
  } else {
    integrator_ = candidate;
  }
  const double unsaturated = p + ff + integrator_;
  const double output = std::clamp(unsaturated, -limit, limit);

  command.value[static_cast<std::size_t>(config_.output_index)] = output;
  terms.term[0] = p;
  terms.term[1] = integrator_;
  terms.term[2] = ff;  // published only when "ff" is among the term names
  fill_terms(terms, {.setpoint = setpoint,
                     .measurement = measurement,
                     .unsaturated = unsaturated,
                     .output = output,
                     .saturated = unsaturated != output,
                     .integrator_held = held});
}

}  // namespace rigctl
