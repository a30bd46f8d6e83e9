#include "rt/control/fuzzy_suspension_controller.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rigctl {

FuzzySuspensionController::FuzzySuspensionController(const FuzzySuspensionConfig& config)
    : config_(config), engine_(config.engine) {
  if (engine_.input_count() != 2) throw std::invalid_argument("fuzzy suspension: the engine must take two inputs");
  if (!(config.force_limit > 0.0)) throw std::invalid_argument("fuzzy suspension: force limit must be positive");
}

void FuzzySuspensionController::update(double setpoint, const Sample& sample, Command& command,
                                       ControllerTerms& terms) noexcept {
  const BodyCorners corners = body_corners(sample, config_.channels, config_.lever_arm);
  std::array<double, 2> raw{}, force{};
  for (std::size_t i = 0; i < 2; ++i) {
    const double x1 = config_.first_input == FuzzyFirstInput::kDisplacement ? setpoint - corners.displacement[i]
                                                                             : -corners.velocity[i];
    const double x2 = -corners.acceleration[i];
    const std::array<double, 2> in{x1, x2};
    raw[i] = engine_.evaluate(in);
    force[i] = std::clamp(raw[i], -config_.force_limit, config_.force_limit);
    terms.term[2 + 2 * i] = x1;
    terms.term[3 + 2 * i] = x2;
  }
  write_forces(command, config_.channels, force[0], force[1]);
  terms.term[0] = force[0];
  terms.term[1] = force[1];
  fill_suspension_terms(terms, setpoint, sample, config_.channels, raw, force);
}

}  // namespace rigctl
