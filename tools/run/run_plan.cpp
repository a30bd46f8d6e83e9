#include "tools/run/run_plan.hpp"

#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "rt/wall_clock.hpp"

namespace rigctl {

namespace {

std::string default_log_path(const std::string& dir, const std::string& rig) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  std::ostringstream name;
  name << rig << "-" << std::put_time(&tm, "%Y%m%d-%H%M%S") << ".lcm";
  std::filesystem::path p = std::filesystem::path(dir) / name.str();
  // Two runs in the same second must not overwrite each other.
  for (int i = 2; std::filesystem::exists(p); ++i) {
    p = std::filesystem::path(dir) / (name.str().substr(0, name.str().size() - 4) + "-" + std::to_string(i) + ".lcm");
  }
  return p.string();
}

// --lock-step: the DAQ cycles once per tick, its poll period the loop's.
RigConfig lock_step_config(RigConfig config) {
  if (config.modbus) {
    config.modbus->lock_step = true;
    config.modbus->poll_period_s = config.loop.period_s;
  }
  return config;
}

// The run's own parts over the config's (the commissioning commands'
// demand and controller), the --fast check and the injected faults.
// Returns the simulated driver, or nullptr on hardware.
SimDriver* apply_run_options(AssembledRig& rig, const RigConfig& config, const RunOptions& options) {
  if (options.profile_override) {
    auto raw = options.profile_override();
    rig.profile_duration_s = raw->duration();
    rig.profile = std::make_unique<FilteredProfile>(std::move(raw), 0.0, config.loop.period_s);
  }
  if (options.more_profile_override) {
    for (std::size_t i = 0; i < rig.more_profiles.size(); ++i) {
      auto raw = options.more_profile_override(i + 1);
      rig.profile_duration_s = std::max(rig.profile_duration_s, raw->duration());
      rig.more_profiles[i] = std::make_unique<FilteredProfile>(std::move(raw), 0.0, config.loop.period_s);
      rig.more_channels[i].profile = rig.more_profiles[i].get();
    }
  }
  if (options.controller_override) rig.controller = options.controller_override(rig.driver->layout());
  if (options.fast && !rig.driver->simulated()) {
    throw std::runtime_error("--fast needs a simulated driver: '" + std::string(to_string(config.driver)) + "' runs real hardware in real time");
  }
  if (options.lock_step && !config.modbus) {
    throw std::runtime_error("--lock-step needs a Modbus DAQ (driver: modbus or modbus_canopen) and `rigctl rig-sim --lock-step` on its far side");
  }
  // Injected faults (drivers/sim/sim_faults.hpp): the config's `faults:`, then --fault.
  std::vector<FaultSpec> faults = config.faults;
  faults.insert(faults.end(), options.faults.begin(), options.faults.end());
  auto* sim = dynamic_cast<SimDriver*>(rig.driver.get());
  if (!faults.empty()) {
    if (sim == nullptr) {
      throw std::runtime_error("faults are injected by the simulated driver (driver: sim); on the wire use `rigctl rig-sim --fault`");
    }
    sim->set_faults(faults);
  }
  return sim;
}

// Operator mode runs until the operator ends it (stop, then hydraulics off)
// or a signal, unless --duration bounds it.
RunLength run_length(const AssembledRig& rig, const RunOptions& options, bool operator_run) {
  RunLength l;
  // A procedure ends the run itself (or a trip holds it until --duration).
  l.unbounded = (operator_run || !options.procedure_path.empty()) && !options.duration_s;
  l.duration_s = options.duration_s.value_or(l.unbounded ? 0.0 : rig.profile_duration_s);
  if (!l.unbounded && !(l.duration_s > 0.0)) throw std::runtime_error("run duration must be positive");
  return l;
}

LoopOptions loop_options_for(const RigConfig& config, const AssembledRig& rig, const RunLength& length) {
  LoopOptions o;
  o.period_ns = std::llround(config.loop.period_s * 1e9);
  o.overrun_policy = config.loop.overrun_policy;
  o.max_ticks = length.unbounded ? std::numeric_limits<int64_t>::max() : std::llround(length.duration_s / config.loop.period_s);
  o.start_from_input = rig.profile_start_input;
  o.timing_every_ticks = std::max<int64_t>(1, std::llround(config.loop.timing_publish_s / config.loop.period_s));
  return o;
}

TelemetryMeta telemetry_meta_for(const RigConfig& config, const AssembledRig& rig, const LoopOptions& loop, bool fast) {
  TelemetryMeta meta;
  meta.rig = to_string(config.rig);
  meta.layout = rig.driver->layout();
  meta.setpoint_name = rig.setpoint_name;
  meta.more_setpoint_names = rig.more_setpoint_names;
  meta.controller_name = rig.controller->name();
  meta.term_names = rig.controller->term_names();
  meta.channel_prefix = config.telemetry.channel_prefix;
  meta.overrun_policy = std::string(to_string(config.loop.overrun_policy));
  meta.period_ns = loop.period_ns;
  meta.start_utime = wall_utime_now();
  // Simulated time has no deadline to keep: a full queue holds the loop back
  // instead of losing records (rt/queue_full_policy.hpp).
  meta.queue_policy = fast ? QueueFullPolicy::kWait : QueueFullPolicy::kDrop;
  return meta;
}

RunRecords run_records(const RigConfig& config, const RunOptions& options, const AssembledRig& rig,
                       const LoopOptions& loop, bool simulated_time) {
  RunRecords r;
  r.log_path = options.log_path.empty() ? default_log_path(config.telemetry.log_dir, std::string(to_string(config.rig))) : options.log_path;
  r.events_path = options.events_path.empty() ? r.log_path + ".events" : options.events_path;
  r.meta = telemetry_meta_for(config, rig, loop, simulated_time);
  r.lcm_url = options.lcm_url.empty() ? config.telemetry.lcm_url : options.lcm_url;
  // Ten seconds of records: a paced run's publisher thread would have to
  // stall that long before the loop drops telemetry.
  r.queue_capacity = options.telemetry_queue_records > 0 ? options.telemetry_queue_records
                                                         : static_cast<std::size_t>(10.0 / config.loop.period_s);
  return r;
}

}  // namespace

RunPlan::RunPlan(const RigConfig& config_file, const RunOptions& options)
    : config(options.lock_step ? lock_step_config(config_file) : config_file),
      simulated_time(options.fast || options.lock_step),
      rig(assemble_rig(config)) {
  sim = apply_run_options(rig, config, options);
  if (sim != nullptr) sim->set_stall_clock(&clock());  // an overrun fault stalls the loop's own clock
  operator_options.force = options.operator_mode;
  operator_options.key_path = options.key_path;
  operator_run = operator_mode(config, operator_options);
  if (operator_run) rig.safety.auto_sequence = false;  // --operator overrides the file
  length = run_length(rig, options, operator_run);
  loop = loop_options_for(config, rig, length);
  records = run_records(config, options, rig, loop, simulated_time);
}

}  // namespace rigctl
