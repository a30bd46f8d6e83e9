// The rig's controller gains and limits as named numbers, SI units, for the
// Foxglove server's read-only parameters (docs/foxglove.md): names are the
// config's keys (controller.kp, limits.x_r.max, safety.detectors.NAME.max).
#pragma once

#include <vector>

#include "config/rig_config.hpp"
#include "foxglove/server/server.hpp"

namespace rigctl {

std::vector<foxglove::Parameter> rig_parameters(const RigConfig& config);

}  // namespace rigctl
