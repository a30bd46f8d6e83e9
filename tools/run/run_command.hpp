// `rigctl run`: load a config, assemble the rig, run the loop with telemetry
// and a run log, report.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "rt/loop/rig_loop.hpp"
#include "drivers/sim/fault_spec.hpp"
#include "rt/comms/telemetry_tap.hpp"
#include "tools/run/ws_endpoint.hpp"
#include "rt/control/controller.hpp"
#include "rt/control/setpoint_profile.hpp"
#include "rt/sample.hpp"

namespace rigctl {

struct RunOptions {
  std::string config_path;
  std::string case_name;             // a `cases:` entry of the config, "" for none
  std::optional<double> duration_s;  // default: the profile's length; operator mode: until the operator ends it
  bool fast = false;                 // simulated plant only: no pacing
  // Hardware driver against `rigctl rig-sim --lock-step` (tests): simulated
  // time as with --fast, one DAQ cycle per tick (ModbusDaqConfig::lock_step).
  bool lock_step = false;
  // Telemetry records the loop can hand over before the queue is full;
  // 0: ten seconds of ticks. A small queue shows the full-queue policy at work.
  std::size_t telemetry_queue_records = 0;
  std::string log_path;              // default: <log_dir>/<rig>-<time>.lcm
  std::string events_path;           // event log; default: <log_path>.events
  std::string csv_path;              // optional run-file CSV
  std::string catalog_path;          // --catalog: the run catalog, over the config's catalog.path (docs/rig-health.md)
  bool csv_truth_channels = true;    // the simulator's sim_* channels in the CSV too
  std::string lcm_url;               // overrides telemetry.lcm_url
  bool realtime = true;              // false: skip mlockall/SCHED_FIFO (tests)
  // Operator commands from a caller's own source (tests); nullptr: in
  // operator mode run_rig opens the LCM command receiver itself
  // (tools/run/operator_mode.hpp). The rig then moves only on these.
  SpscQueue<OperatorCommand>* operator_commands = nullptr;
  bool operator_mode = false;  // --operator: safety.auto_sequence taken as false
  std::string key_path;        // --key: overrides operator.key_file
  // --fault KIND@TIME[:ARG...], after the config's `faults:`; simulated driver only (drivers/sim/sim_faults.hpp).
  std::vector<FaultSpec> faults;
  // --ws [ADDR:]PORT: the Foxglove WebSocket server, over telemetry.websocket (docs/foxglove.md).
  std::optional<WsEndpoint> websocket;
  // Further consumers of every telemetry message, called before the Foxglove
  // server's feed (rigctl bench: the time each message left the publisher).
  std::vector<TelemetryTap*> telemetry_taps;
  // Parts that replace the config's, for the commissioning commands
  // (rigctl identify, rigctl tune --method relay): the demand (an excitation
  // about an operating point, applied unfiltered; its length is the run's
  // default length) and the controller (a relay experiment), built for the
  // assembled rig's channels. Everything else, the safety machinery above
  // all, is the config's.
  std::function<std::unique_ptr<SetpointProfile>()> profile_override;
  // The same for the control channels after the first (`channels:`), by
  // their 0-based index (1: the second channel): a multi-channel
  // identification or drive excites every channel.
  std::function<std::unique_ptr<SetpointProfile>(std::size_t channel)> more_profile_override;
  std::function<std::unique_ptr<Controller>(const ChannelLayout&)> controller_override;
  // --procedure PROC.yaml: a test procedure gives the demand and ends the run
  // (docs/procedures.md); --resume RECOVERY continues one; the recovery is
  // written to recovery_path (default: <log>.recovery).
  std::string procedure_path;
  std::string resume_path;
  std::string recovery_path;
};

struct RunReport {
  LoopResult loop;
  std::string log_path;
  std::string csv_path;
  std::string events_path;
  int64_t catalog_run_id = 0;  // the run's id in the catalog, 0: not entered
  std::string end_reason;  // why the run ended, e.g. "sensor_stuck: x_r = 0.0348"
  double wall_s = 0.0;
};

// Throws ConfigError or std::runtime_error with a clear message; `stop`
// ends the run early (signal handlers set it).
RunReport run_rig(const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out);
// The same with a config already loaded (and possibly edited: the hidden-effect
// generator); options.config_path and case_name are then only reported.
RunReport run_rig(const RigConfig& config, const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
