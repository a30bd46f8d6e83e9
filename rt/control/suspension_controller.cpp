#include "rt/control/suspension_controller.hpp"

namespace rigctl {

BodyCorners body_corners(const Sample& s, const SuspensionChannels& ch, const LeverArms& lever) noexcept {
  BodyCorners c;
  const double zs = sample_at(s, ch.z_s), phi = sample_at(s, ch.phi);
  const double vs = sample_at(s, ch.z_s_dot), omega = sample_at(s, ch.phi_dot);
  const double as = sample_at(s, ch.z_s_ddot), alpha = sample_at(s, ch.phi_ddot);
  for (std::size_t i = 0; i < 2; ++i) {
    c.displacement[i] = zs + lever[i] * phi;
    c.velocity[i] = vs + lever[i] * omega;
    c.acceleration[i] = as + lever[i] * alpha;
  }
  return c;
}

void write_forces(Command& command, const SuspensionChannels& ch, double f1, double f2) noexcept {
  command.value[static_cast<std::size_t>(ch.output_1)] = f1;
  command.value[static_cast<std::size_t>(ch.output_2)] = f2;
}

void fill_suspension_terms(ControllerTerms& terms, double setpoint, const Sample& sample, const SuspensionChannels& ch,
                           const std::array<double, 2>& raw, const std::array<double, 2>& force) noexcept {
  fill_terms(terms, {.setpoint = setpoint,
                     .measurement = sample_at(sample, ch.z_s),
                     .unsaturated = raw[0],
                     .output = force[0],
                     .saturated = raw[0] != force[0] || raw[1] != force[1]});
}

void PassiveSuspensionController::update(double setpoint, const Sample& sample, Command& command,
                                         ControllerTerms& terms) noexcept {
  write_forces(command, channels_, 0.0, 0.0);
  fill_suspension_terms(terms, setpoint, sample, channels_, {0.0, 0.0}, {0.0, 0.0});
}

}  // namespace rigctl
