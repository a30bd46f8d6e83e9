// What one `rigctl run` is, settled before anything starts: the config (with
// --lock-step's DAQ settings), the rig assembled with the run's own parts,
// operator mode, the run's length, the loop's options and clock, and where
// its records go. Every refusal of the options (--fast on hardware, a
// non-positive length, faults on a driver that cannot inject them) is thrown
// from here, before a file is written or a thread started.
#pragma once

#include <cstddef>
#include <string>

#include "config/rig_config.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "rt/loop/rig_loop.hpp"
#include "rt/loop_clock.hpp"
#include "tools/run/operator_mode.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl {

struct RunLength {
  bool unbounded = false;  // operator mode (or a procedure) without --duration: until it ends itself
  double duration_s = 0.0;
};

// Where the run's records go and how.
struct RunRecords {
  TelemetryMeta meta;
  std::string lcm_url;      // --lcm-url over telemetry.lcm_url
  std::string log_path;     // --log, else a new file in the config's log_dir
  std::string events_path;  // --events, else <log>.events
  std::size_t queue_capacity = 0;  // telemetry records the loop can hand over before the queue is full
};

struct RunPlan {
  // Throws ConfigError or std::runtime_error naming the option refused.
  RunPlan(const RigConfig& config_file, const RunOptions& options);
  RunPlan(const RunPlan&) = delete;
  RunPlan& operator=(const RunPlan&) = delete;

  // The loop's clock: the tick count in simulated time, else the monotonic clock.
  LoopClock& clock() { return simulated_time ? static_cast<LoopClock&>(virtual_clock) : monotonic; }

  const RigConfig config;
  bool simulated_time = false;  // --fast, --lock-step
  MonotonicClock monotonic;
  VirtualClock virtual_clock;  // before the rig: the simulated driver stalls on it (an overrun fault)
  AssembledRig rig;
  SimDriver* sim = nullptr;  // the simulated driver, nullptr on hardware
  OperatorModeOptions operator_options;
  bool operator_run = false;  // the rig powers up faulted and moves only on operator commands
  RunLength length;
  LoopOptions loop;
  RunRecords records;
};

}  // namespace rigctl
