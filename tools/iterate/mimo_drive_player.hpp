// Plays one drive per control channel of a multi-channel rig (the
// two-poster's posts) through the normal run path (`run_rig`: the config's
// assembly, loop, limit detectors and state machine) and returns the asked
// channels tick for tick beside the drives. Each channel's demand: its
// lead-in to its operating point, a settling hold (the lead-ins aligned so
// that the drives start together), its drive, its operating point again
// until the run's controlled stop: the one-channel player's demand
// (drive_player.hpp) on every channel.
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/iterate/drive_player.hpp"

namespace rigctl {

struct MimoPlayResult {
  bool completed = false;
  std::string end_reason;                       // why the run ended when it did not complete
  std::vector<std::vector<double>> channels;    // the asked channels over the drives' ticks
  double drive_start_s = 0.0;                   // run-file time of the drives' first tick
};

// drives: one record per control channel, absolute demands (the channel's
// operating point plus the drive), all of one length; operating_points: the
// channels' rest levels. settings.operating_point is not used.
MimoPlayResult play_drives(const RigConfig& config, const std::vector<std::vector<double>>& drives,
                           const std::vector<double>& operating_points, const std::vector<std::string>& channels,
                           const PlaySettings& settings, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
