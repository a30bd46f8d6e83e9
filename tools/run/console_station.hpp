// The console's station description (foxglove/console/station.hpp) from a
// rig's config and its driver's channels: its limit detectors with their
// thresholds and actions, and the scope's default channels (demand,
// feedback, valve commands, pressures).
#pragma once

#include <string>

#include "config/rig_config.hpp"
#include "foxglove/console/station.hpp"
#include "rt/sample.hpp"

namespace rigctl {

foxglove::StationDescription console_station(const RigConfig& config, const ChannelLayout& layout,
                                             const std::string& setpoint_name);

}  // namespace rigctl
