#include "rt/control/pvp_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rigctl {

PvpController::PvpController(const PvpConfig& config) : config_(config) {
  if (config.period_s <= 0.0) throw std::invalid_argument("controller period must be positive");
  if (config.output_limit <= 0.0) throw std::invalid_argument("controller output limit must be positive");
  if (config.tau_f <= 0.0) throw std::invalid_argument("transient pressure time constant must be positive");
  velocity_alpha_ =
      config.velocity_filter_tau > 0.0 ? 1.0 - std::exp(-config.period_s / config.velocity_filter_tau) : 1.0;
  // Backward-difference (Tustin would ring at Nyquist with the dither):
  // y_k = a (y_{k-1} + x_k - x_{k-1}), a = tau / (tau + Ts).
  highpass_a_ = config.tau_f / (config.tau_f + config.period_s);
}

void PvpController::reset() noexcept {
  primed_ = false;
  omega_ = transient_ = 0.0;
}

void PvpController::update(double setpoint, const Sample& sample, Command& command,
                           ControllerTerms& terms) noexcept {
  const double angle = sample.value[static_cast<std::size_t>(config_.angle_input)];
  const double pressure = sample.value[static_cast<std::size_t>(config_.pressure_input)];
  if (!primed_) {
    last_angle_ = angle;
    last_pressure_ = pressure;
    primed_ = true;
  }
  omega_ += velocity_alpha_ * ((angle - last_angle_) / config_.period_s - omega_);
  transient_ = highpass_a_ * (transient_ + pressure - last_pressure_);
  last_angle_ = angle;
  last_pressure_ = pressure;

  const double error = setpoint - angle;
  const double e_part = config_.ke * error;
  const double p_part = -config_.kp * (config_.transient_pressure ? transient_ : pressure);
  const double v_part = -config_.kv * omega_;
  const double unsaturated = e_part + p_part + v_part;
  const double output = std::clamp(unsaturated, -config_.output_limit, config_.output_limit);

  command.value[static_cast<std::size_t>(config_.output_index)] = output;
  terms.term[0] = e_part;
  terms.term[1] = p_part;
  terms.term[2] = v_part;
  terms.term[3] = omega_;
  fill_terms(terms, {.setpoint = setpoint,
                     .measurement = angle,
                     .unsaturated = unsaturated,
                     .output = output,
                     .saturated = unsaturated != output});
}

}  // namespace rigctl
