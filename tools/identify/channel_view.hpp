// One control channel of a multi-channel rig (`channels:`) as the
// one-channel commissioning code sees a config: that channel's controller
// and profile in the top-level sections, everything else (the plant, the
// limits, the safety machinery) the rig's. Channel 0 is the config itself.
#pragma once

#include <cstddef>
#include <string>

#include "config/rig_config.hpp"

namespace rigctl {

inline std::size_t channel_count(const RigConfig& c) { return 1 + c.more_channels.size(); }

inline RigConfig channel_view(const RigConfig& c, std::size_t channel) {
  if (channel == 0) return c;
  RigConfig one = c;
  one.controller = c.more_channels.at(channel - 1).controller;
  one.profile = c.more_channels.at(channel - 1).profile;
  return one;
}

// The run-file name of channel i's demand: x_ref_1, x_ref_2, ... (rig_assembly's names).
inline std::string channel_setpoint_name(const std::string& setpoint, std::size_t channel) {
  return setpoint + "_" + std::to_string(channel + 1);
}

}  // namespace rigctl
