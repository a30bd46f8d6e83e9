#include "rt/control/skyhook_controller.hpp"

#include <algorithm>
#include <stdexcept>

namespace rigctl {

SkyhookController::SkyhookController(const SkyhookConfig& config) : config_(config) {
  if (!(config.c_sky >= 0.0)) throw std::invalid_argument("skyhook: c_sky must not be negative");
  if (!(config.force_limit > 0.0)) throw std::invalid_argument("skyhook: force limit must be positive");
}

void SkyhookController::update(double setpoint, const Sample& sample, Command& command,
                               ControllerTerms& terms) noexcept {
  const BodyCorners corners = body_corners(sample, config_.channels, config_.lever_arm);
  std::array<double, 2> raw{}, force{};
  for (std::size_t i = 0; i < 2; ++i) {
    raw[i] = -config_.c_sky * corners.velocity[i];
    force[i] = std::clamp(raw[i], -config_.force_limit, config_.force_limit);
  }
  write_forces(command, config_.channels, force[0], force[1]);
  terms.term[0] = force[0];
  terms.term[1] = force[1];
  terms.term[2] = corners.velocity[0];
  terms.term[3] = corners.velocity[1];
  fill_suspension_terms(terms, setpoint, sample, config_.channels, raw, force);
}

}  // namespace rigctl
