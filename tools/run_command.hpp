// `rigctl run`: load a config, assemble the rig, run the loop with telemetry
// and a run log, report.
#pragma once

#include <atomic>
#include <optional>
#include <ostream>
#include <string>

#include "config/rig_config.hpp"
#include "rt/rig_loop.hpp"

namespace rigctl {

struct RunOptions {
  std::string config_path;
  std::string case_name;             // a `cases:` entry of the config, "" for none
  std::optional<double> duration_s;  // default: the profile's length
  bool fast = false;                 // simulated plant only: no pacing
  std::string log_path;              // default: <log_dir>/<rig>-<time>.lcm
  std::string events_path;           // event log; default: <log_path>.events
  std::string csv_path;              // optional run-file CSV
  std::string lcm_url;               // overrides telemetry.lcm_url
  bool realtime = true;              // false: skip mlockall/SCHED_FIFO (tests)
  // Operator commands (the LCM command receiver pushes them); nullptr: none.
  // With `safety.auto_sequence: false` the rig then moves only on these.
  SpscQueue<OperatorCommand>* operator_commands = nullptr;
};

struct RunReport {
  LoopResult loop;
  std::string log_path;
  std::string csv_path;
  std::string events_path;
  double wall_s = 0.0;
};

// Throws ConfigError or std::runtime_error with a clear message; `stop`
// ends the run early (signal handlers set it).
RunReport run_rig(const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out);
// The same with a config already loaded (and possibly edited: the hidden-effect
// generator); options.config_path and case_name are then only reported.
RunReport run_rig(const RigConfig& config, const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
