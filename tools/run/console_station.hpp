// The console's station description (foxglove/console/station.hpp) from a
// rig's config and its driver's channels: its limit detectors with their
// thresholds and actions, and the scope's default channels (demand,
// feedback, valve commands, pressures).
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "foxglove/console/station.hpp"
#include "rt/sample.hpp"

namespace rigctl {

// more_setpoint_names: the demands of the control channels after the first
// (x_ref_2, ...), empty on a one-channel rig.
foxglove::StationDescription console_station(const RigConfig& config, const ChannelLayout& layout,
                                             const std::string& setpoint_name,
                                             const std::vector<std::string>& more_setpoint_names = {});

}  // namespace rigctl
