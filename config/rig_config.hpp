// The whole configuration of one rig run, parsed and checked. Everything here
// is SI; conversions (degrees, channel names to indices) happen at load.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "config/controller_kind.hpp"
#include "config/detector_kinds.hpp"
#include "config/driver_kind.hpp"
#include "config/identify_config.hpp"
#include "config/operator_config.hpp"
#include "config/profile_kind.hpp"
#include "config/rig_kind.hpp"
#include "config/suspension_settings.hpp"
#include "drivers/canopen/canopen_valve_config.hpp"
#include "drivers/modbus/modbus_daq_config.hpp"
#include "drivers/sim/sensor_model.hpp"
#include "plant/half_car/half_car_params.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_params.hpp"
#include "plant/quarter_car/quarter_car_params.hpp"
#include "plant/two_poster/two_poster_plant.hpp"
#include "rt/safety/limit_action.hpp"
#include "rt/control/pi_controller.hpp"
#include "rt/control/pvp_controller.hpp"
#include "rt/realtime.hpp"
#include "rt/timing_stats.hpp"
#include "drivers/sim/fault_spec.hpp"

namespace rigctl {

struct LoopConfig {
  double period_s = 0.0025;
  OverrunPolicy overrun_policy = OverrunPolicy::kSkip;
  double timing_publish_s = 1.0;
  RealtimeConfig realtime;
};

// `telemetry.websocket` (optional): the Foxglove WebSocket server of
// `rigctl run` (docs/foxglove.md); `--ws` overrides it.
struct WebsocketConfig {
  std::string address = "127.0.0.1";  // loopback: another address only when the config says so
  int port = 8765;                    // Foxglove's default; 0: any free port
  int client_queue_messages = 1024;   // per client, oldest dropped when full (foxglove/server/server.hpp)
  int max_clients = 16;               // WebSocket clients at once; the next is refused with HTTP 503
  std::vector<std::string> allowed_origins;  // pages of these origins may connect besides the server's own (a reverse proxy's)
  // Control held by a console that has answered no ping for this long is
  // released. 3 s: three ping intervals, so one late pong on a busy network
  // keeps control, while a closed laptop or a pulled cable frees it before
  // an operator at another station has walked over (stop and hold never
  // need control).
  double control_timeout_s = 3.0;
  // A client that has answered no ping for this long is closed: long enough
  // for a client to ride out a network hiccup, short enough that a vanished
  // peer or a half-sent frame does not keep its connection for long.
  double client_timeout_s = 10.0;
};

struct TelemetryConfig {
  std::string lcm_url = "memq://";
  std::string channel_prefix = "RIGCTL_";
  std::string log_dir = "runs";
  std::optional<WebsocketConfig> websocket;
};

// `catalog:` (optional): the run catalog of this rig PC (docs/rig-health.md),
// one SQLite file that `rigctl run` enters every run into; `--catalog`
// overrides the path. Without it (and without --catalog) no run is entered.
struct CatalogConfig {
  std::string path;      // relative to the working directory, like telemetry.log_dir
  std::string rig_name;  // this rig's name in the lab; default: the rig kind (quarter_car)
};

struct ControllerConfig {
  ControllerKind type = ControllerKind::kPi;  // one of the rig's own (rig_of)
  std::string feedback;     // input channel name
  std::string output;       // output channel name (half_car: suspension.output_1 and _2)
  PiConfig pi;              // type pi; channel indices resolved when the rig is assembled
  PvpConfig pvp;            // type pvp
  std::string pressure;     // type pvp: differential-pressure input channel
  SuspensionControllerSettings suspension;  // half_car: every controller's settings (compare runs them all)
};

struct ProfileConfig {
  ProfileKind type = ProfileKind::kRampSteps;
  double filter_tau_s = 0.0;
  // ramp_steps and sine; positions in the feedback channel's unit (m or rad)
  double start = 0.0, hold_s = 0.0, ramp_target = 0.0, ramp_rate = 0.0;
  bool start_from_measurement = false;  // `start: measured`: begin where the rig stands
  std::vector<double> steps;  // ramp_steps
  double step_hold_s = 0.0;
  double amplitude = 0.0, frequency_hz = 0.0, cycles = 0.0;  // sine
  std::string csv_file;    // csv: path resolved against the config's folder
  std::string csv_column;  // csv: column with the demand
  double value = 0.0, duration_s = 0.0;  // hold: a constant demand for duration_s
};

// A control channel after the first of a rig with several actuators
// (`channels:`, a list whose first entry is `controller`/`profile`).
struct ChannelConfig {
  ControllerConfig controller;
  ProfileConfig profile;
};

struct LimitConfig {
  std::string channel;
  double min = 0.0, max = 0.0;
};

// The `safety:` section (config/safety_config.cpp): the state machine's
// ramps and staging, the action of the `limits:` ranges, and the limit
// detectors. Channel names are resolved when the rig is assembled
// (tools/run/rig_assembly.cpp), with errors naming safety.detectors.NAME.
struct DetectorConfig {
  std::string name;     // key under safety.detectors
  DetectorKind type = DetectorKind::kRange;  // any but kInvalid (config/detector_kinds.hpp)
  std::string channel;  // input; valve_saturation and stuck: `output` goes to output; tracking_error: default controller.feedback
  std::string output;   // valve_saturation, stuck: the valve output
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  double duration_s = 0.0;
  double tolerance = 0.0;
  double command_min = 0.0;
  int64_t max_count = 0;
  double window_s = 1.0;
  LimitAction action = LimitAction::kInterlock;
  bool latch = true;
};

struct SafetyConfig {
  bool auto_sequence = true;       // `rigctl run` without an operator
  double low_settle_s = 0.0;       // timed hydraulic staging
  double high_settle_s = 0.0;
  double hold_deceleration = 1.0;  // [unit/s^2] of the feedback channel
  double setpoint_rate = 0.05;     // [unit/s]
  double setpoint_min = -std::numeric_limits<double>::infinity();
  double setpoint_max = std::numeric_limits<double>::infinity();
  double stop_timeout_s = 5.0;
  LimitAction limits_action = LimitAction::kInterlock;  // action of the `limits:` ranges
  std::vector<DetectorConfig> detectors;
};


LimitAction limit_action_from_string(const std::string& s);

struct RigConfig {
  std::string file;
  std::string case_name;  // the `cases:` entry applied, "" for none
  RigKind rig = RigKind::kQuarterCar;
  DriverKind driver = DriverKind::kSim;
  double driver_start_timeout_s = 2.0;  // hardware: first sample / valve operational within this
  uint64_t seed = 1;
  LoopConfig loop;
  TelemetryConfig telemetry;
  // The first control channel: `controller:` and `profile:`, or the first
  // entry of `channels:` (a list of {controller, profile}, one per actuator).
  ControllerConfig controller;
  ProfileConfig profile;
  std::vector<ChannelConfig> more_channels;  // `channels:` after the first; empty for one channel
  std::vector<LimitConfig> limits;
  SafetyConfig safety;  // `safety:`; optional, defaults as SafetyConfig{}
  OperatorConfig operator_commands;  // `operator:`; optional (config/operator_config.hpp)
  std::vector<FaultSpec> faults;     // `faults:`; optional list of KIND@TIME[:ARG...] (drivers/sim/sim_faults.hpp)
  IdentifyConfig identify;           // `identify:`; optional (config/identify_config.hpp)
  std::optional<CatalogConfig> catalog;  // `catalog:`; optional
  QuarterCarParams quarter_car;          // rig quarter_car
  PneumaticRotaryParams pneumatic_rotary;  // rig pneumatic_rotary
  HalfCarParams half_car;                  // rig half_car
  TwoPosterParams two_poster;              // rig two_poster
  SuspensionReportConfig suspension_report;      // half_car `report:` (rigctl compare)
  SuspensionOptimizeConfig suspension_optimize;  // half_car `optimize:` (rigctl optimize)
  std::map<std::string, SensorSpec> sensors;  // by channel name
  std::map<std::string, SensorSpec> dacs;     // output converters, by output name (noise unused)
  // The physical rig's I/O (and what `rigctl rig-sim` exposes): required by
  // the drivers that use them, optional otherwise.
  std::optional<ModbusDaqConfig> modbus;
  std::optional<CanopenValveConfig> canopen;
};

// Throws ConfigError naming file, line, key and reason. case_name selects an
// entry of the file's optional `cases:` map, merged over the rest (the
// paper's ready-made variants); "" uses the file as it is.
RigConfig load_rig_config(const std::string& path, const std::string& case_name = "");
RigConfig parse_rig_config(const std::string& yaml_text, const std::string& name, const std::string& case_name = "");
// Names of the `cases:` entries of a config file.
std::vector<std::string> config_case_names(const std::string& path);

}  // namespace rigctl
