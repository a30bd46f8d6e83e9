// Plays one drive on the rig through the normal run path (`run_rig`: the
// config's assembly, loop, limit detectors and state machine, every limit
// and interlock active) as the demand, and returns the target channel's
// response, tick for tick beside the drive. The demand: the config's
// lead-in to the operating point, a settling hold, the drive, the
// operating point again until the run's controlled stop
// (tools/identify/excitation_profile.hpp, the identification's demand).
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"

namespace rigctl {

struct PlaySettings {
  double operating_point = 0.0;  // [feedback unit] the drive's rest level (its first and last value)
  double settle_s = 5.0;         // [s] held there before the drive: the PI integrator takes up the leakage (~1 s) and the body settles on its bearing
  bool fast = false;             // simulated rigs: simulated time
  bool realtime = true;
  std::string csv_path;          // the run's run file (kept: the iteration's record)
  std::string log_path;          // the run's LCM log
};

struct PlayResult {
  bool completed = false;        // false: a limit tripped or a stop was requested
  std::string end_reason;        // why the run ended when it did not complete
  std::vector<double> response;  // the channel over the drive's ticks
  std::vector<double> feedback;  // the controller's feedback (the rod) over them
  std::vector<double> command;   // the controller's output (the valve command) over them
  double drive_start_s = 0.0;    // run-file time of the drive's first tick
};

PlayResult play_drive(const RigConfig& config, const std::vector<double>& drive, const std::string& channel,
                      const PlaySettings& settings, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
