#include "tools/common/stage_text.hpp"
#include "rt/wall_clock.hpp"
#include "tools/run/run_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "rt/comms/event_log.hpp"
#include "rt/realtime.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "tools/run/console_station.hpp"
#include "tools/run/console_status.hpp"
#include "tools/runfile/log2csv.hpp"
#include "tools/run/loop_heartbeat.hpp"
#include "tools/run/operator_mode.hpp"
#include "foxglove/telemetry/telemetry_server.hpp"
#include "tools/run/rig_parameters.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/run/run_catalog.hpp"
#include "tools/run/service_notify.hpp"
#include "tools/procedure/procedure_run.hpp"

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

std::string describe(const DistributionSummary& d) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(1) << "p50 " << d.p50_ns / 1e3 << " us, p99 " << d.p99_ns / 1e3
     << " us, p99.9 " << d.p999_ns / 1e3 << " us, max " << d.max_ns / 1e3 << " us";
  return os.str();
}

// Why the run ended, for the console: the event and its channel, or, for an
// input the driver flagged and knows why (a CANopen valve's heartbeat lost,
// EMCY, reset, device state), the driver's cause.
std::string end_reason(const Event& e, const ChannelLayout& layout, const Driver& driver) {
  std::ostringstream os;
  const auto index = static_cast<std::size_t>(e.channel);
  if (e.code == EventCode::kInputInvalid && e.channel >= 0) {
    const std::string cause = driver.input_fault_cause(index);
    if (!cause.empty()) {
      os << cause << "; input " << (index < layout.inputs.size() ? layout.inputs[index].name : "?") << " flagged invalid";
      return os.str();
    }
  }
  os << to_string(e.code);
  if (e.channel >= 0) {
    // Valve saturation names an output; every other trip an input.
    const auto& channels = e.code == EventCode::kValveSaturated ? layout.outputs : layout.inputs;
    os << ": " << (index < channels.size() ? channels[index].name : "?") << " = " << e.value;
  }
  return os.str();
}

// The Foxglove server of the run, when the config or --ws asks for one.
// Its page at `/` is the operator console, which takes signed commands in
// operator mode (docs/console.md).
std::unique_ptr<foxglove::TelemetryServer> make_foxglove_server(const RigConfig& config, const RunOptions& options,
                                                                const foxglove::StationDescription& station) {
  const auto ws = websocket_settings(config.telemetry.websocket, options.websocket);
  if (!ws) return nullptr;
  foxglove::ServerOptions so = server_options(*ws);
  so.name = "rigctl " + std::string(to_string(config.rig));
  so.metadata = {{"rig", std::string(to_string(config.rig))},
                 {"driver", std::string(to_string(config.driver))},
                 {"config", options.config_path},
                 {foxglove::kStationMetadataKey, foxglove::station_json(station)}};
  return std::make_unique<foxglove::TelemetryServer>(so, config.telemetry.channel_prefix, rig_parameters(config));
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

struct RunLength {
  bool unbounded = false;  // operator mode without --duration: until the operator ends it
  double duration_s = 0.0;
};

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

void print_run_header(const RigConfig& config, const RunOptions& options, const RunLength& length,
                      const TelemetryMeta& meta, const std::string& url, const foxglove::TelemetryServer* server,
                      const CommandReceiver* receiver, std::ostream& out) {
  out << "rigctl run: " << config.rig << " (" << config.driver << " driver) from " << options.config_path
      << (options.case_name.empty() ? "" : " case " + options.case_name) << ", "
      << (length.unbounded ? std::string("until stopped") : fmt::format("{:g} s", length.duration_s)) << " "
      << (options.fast ? "as fast as possible" : options.lock_step ? "in lock-step with rig-sim" : "paced by the real clock") << "\n"
      << "  telemetry: " << url << " channels " << config.telemetry.channel_prefix << "*, a full queue "
      << (meta.queue_policy == QueueFullPolicy::kWait ? "holds the loop back (simulated time: nothing is dropped)"
                                                       : "drops and counts (the tick never waits)")
      << "\n";
  if (server) {
    out << "  foxglove: " << server->url() << " serves " << config.telemetry.channel_prefix
        << "* as JSON (Foxglove, Lichtblick; docs/foxglove.md)\n";
  }
  if (receiver) {
    out << "  operator mode: the rig powers up faulted; commands on " << receiver->channel() << " (acks on "
        << receiver->ack_channel() << ")\n";
  }
  out.flush();
}

// How the run ended and how the loop kept its period.
void print_run_summary(const RigConfig& config, const RunOptions& options, const RunReport& report,
                       const Driver& driver, std::ostream& out) {
  const LoopResult& result = report.loop;
  const auto& t = result.timing;
  out << "  ended: " << to_string(result.final_state) << " (" << report.end_reason << ") after " << result.ticks << " ticks ("
      << std::fixed << std::setprecision(3) << static_cast<double>(result.ticks) * config.loop.period_s
      << " s rig time, " << report.wall_s << " s wall), rig state " << to_string(result.final_safety_state) << "\n";
  if (!options.fast && !options.lock_step) {
    out << "  wake-up latency: " << describe(t.wakeup_latency) << "\n"
        << "  compute per tick: " << describe(t.compute) << "\n"
        << "    longest per step: " << describe_stages(t.stages.max_ns) << "\n"
        << "    slowest tick (" << t.stages.slowest_tick << "): " << describe_stages(t.stages.slowest_tick_ns) << "\n"
        << (driver.io_latency().count > 0 ? "  I/O round trip: " + describe(driver.io_latency()) + "\n" : "")
        << "  overruns: " << t.overruns << " (missed ticks " << t.missed_ticks << ", policy "
        << to_string(config.loop.overrun_policy) << ")\n";
  }
  if (result.dropped_records > 0) out << "  telemetry records dropped: " << result.dropped_records << "\n";
}

// The operator's command receiver of an operator-mode run, on the run's LCM
// URL, with the unit of the setpoint commands (the loop's feedback input).
std::unique_ptr<CommandReceiver> open_command_receiver(const RigConfig& config, const AssembledRig& rig,
                                                       const std::string& url, OperatorModeOptions op, EventLog& events) {
  op.lcm_url = url;
  const auto feedback = static_cast<std::size_t>(std::max(0, rig.safety.feedback_input));
  const auto& inputs = rig.driver->layout().inputs;
  op.setpoint_unit = feedback < inputs.size() ? inputs[feedback].unit : "";
  return make_operator_receiver(config, op, events);
}

// Where the run's records went, and anything that did not get there.
void print_run_records(const RunReport& report, const TelemetryPublisher& publisher, const EventLog& events,
                       const CommandReceiver* receiver, const foxglove::TelemetryServer* server, std::ostream& out) {
  if (publisher.queue_waits() > 0) {
    out << "  telemetry queue full " << publisher.queue_waits() << " times: the loop waited for the publisher\n";
  }
  out << "  log: " << report.log_path << "\n";
  const EventLogStats es = events.stats();
  out << "  events: " << report.events_path << " (" << es.written << " lines, " << std::setprecision(2)
      << "longest write+fsync " << es.max_fsync_ms << " ms" << (es.pending > 0 ? ", " + std::to_string(es.pending) + " NOT WRITTEN" : "")
      << ")\n";
  if (receiver) out << "  operator commands: " << describe_counters(receiver->counters()) << "\n";
  if (server) out << "  foxglove: " << server->describe_clients() << "\n";
  if (publisher.log_failures() > 0) out << "  run log write failures: " << publisher.log_failures() << "\n";
}

// --lock-step: the DAQ cycles once per tick, its poll period the loop's.
RigConfig lock_step_config(RigConfig config) {
  if (config.modbus) {
    config.modbus->lock_step = true;
    config.modbus->poll_period_s = config.loop.period_s;
  }
  return config;
}

}  // namespace

RunReport run_rig(const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  return run_rig(load_rig_config(options.config_path, options.case_name), options, stop, out);
}

RunReport run_rig(const RigConfig& config_file, const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  const RigConfig config = options.lock_step ? lock_step_config(config_file) : config_file;
  // Simulated time: the loop's clock is the tick count (--fast, --lock-step).
  const bool simulated_time = options.fast || options.lock_step;
  AssembledRig rig = assemble_rig(config);
  SimDriver* sim = apply_run_options(rig, config, options);

  OperatorModeOptions op;
  op.force = options.operator_mode;
  op.key_path = options.key_path;
  const bool operator_run = operator_mode(config, op);
  if (operator_run) rig.safety.auto_sequence = false;  // --operator overrides the file
  const RunLength length = run_length(rig, options, operator_run);
  const LoopOptions loop_options = loop_options_for(config, rig, length);

  RunReport report;
  report.log_path = options.log_path.empty() ? default_log_path(config.telemetry.log_dir, std::string(to_string(config.rig))) : options.log_path;
  report.csv_path = options.csv_path;
  std::unique_ptr<ProcedureRun> procedure;
  ProcedureRunOptions po;
  if (!options.procedure_path.empty()) {
    po.procedure_path = options.procedure_path;
    po.resume_path = options.resume_path;
    po.recovery_path = options.recovery_path.empty() ? report.log_path + ".recovery" : options.recovery_path;
    po.config_path = options.config_path;
    po.case_name = options.case_name;
    po.fast = options.fast;
    po.period_s = config.loop.period_s;
    procedure = open_procedure_run(po, rig.driver->layout(), std::max(0, rig.safety.feedback_input));
  } else if (!options.resume_path.empty()) {
    throw std::runtime_error("--resume continues a procedure: give its --procedure too");
  }
  const TelemetryMeta meta = telemetry_meta_for(config, rig, loop_options, simulated_time);
  const std::string url = options.lcm_url.empty() ? config.telemetry.lcm_url : options.lcm_url;
  // Ten seconds of records: a paced run's publisher thread would have to
  // stall that long before the loop drops telemetry.
  const auto queue_capacity = options.telemetry_queue_records > 0
                                  ? options.telemetry_queue_records
                                  : static_cast<std::size_t>(10.0 / config.loop.period_s);
  // Before the publisher: the publisher's last messages at its stop still
  // reach the server's feed.
  foxglove::StationDescription station = console_station(config, rig.driver->layout(), rig.setpoint_name, rig.more_setpoint_names);
  station.commands = operator_run && options.operator_commands == nullptr;  // the run's own receiver takes them
  const auto foxglove_server = make_foxglove_server(config, options, station);
  TelemetryPublisher publisher(meta, url, report.log_path, queue_capacity);
  for (TelemetryTap* tap : options.telemetry_taps) publisher.add_tap(tap);
  if (foxglove_server) publisher.add_tap(&foxglove_server->tap());
  Driver* driver = rig.driver.get();
  publisher.set_diagnostics_source([driver] { return driver->diagnostics(); }, std::string(to_string(config.driver)));

  // The event log: every state change, trip and command, fsync'd per line.
  report.events_path = options.events_path.empty() ? report.log_path + ".events" : options.events_path;
  EventLog events(report.events_path, EventLogMeta{meta.rig, rig.driver->layout(), meta.start_utime, meta.queue_policy});
  events.set_failure_handler([&publisher](const std::string& text) {
    spdlog::error("{}", text);
    publisher.report_event("log_write_failed", text);
  });
  if (foxglove_server) foxglove_server->log_to(events);
  std::unique_ptr<CommandReceiver> receiver;
  SpscQueue<OperatorCommand>* commands = options.operator_commands;
  if (operator_run && commands == nullptr) {
    receiver = open_command_receiver(config, rig, url, op, events);
    commands = &receiver->queue();
    if (foxglove_server) {
      foxglove_server->enable_console_commands(receiver->intake(),
                                               websocket_settings(config.telemetry.websocket, options.websocket)->control_timeout_s);
    }
  }
  // The console's gateway hands commands to the receiver from the server's
  // thread: on any way out of this function the server stops before the
  // receiver goes (this guard, declared after it, is destroyed first).
  struct StopServer {
    foxglove::TelemetryServer* server;
    ~StopServer() {
      if (server != nullptr) server->stop();
    }
  } const stop_console_before_receiver{receiver ? foxglove_server.get() : nullptr};
  // Counts the loop's ticks for the systemd watchdog (a no-op outside systemd).
  LoopHeartbeat heartbeat(publisher);
  ServiceNotifier notifier(heartbeat.beats());

  rig.driver->start();
  publisher.start();  // before the real-time set-up: the publisher keeps normal priority
  if (foxglove_server) foxglove_server->start();  // likewise
  events.start();
  // Threads started before the RealtimeSession keep normal priority.
  if (receiver) receiver->start();
  notifier.start();
  // The one way down, after the loop or on its failure: the receiver before
  // the event log (its last rejections go in), the logs kept (what was
  // recorded stays), the driver last (the valve stays safe until then).
  if (procedure) procedure->writer->start();
  auto stop_services = [&](const char* why) {
    if (procedure) procedure->writer->stop();  // its last recovery written
    notifier.stop(why);
    if (receiver) receiver->stop();
    events.stop();
    publisher.stop();
    if (foxglove_server) foxglove_server->stop();
    rig.driver->stop();
  };

  print_run_header(config, options, length, meta, url, foxglove_server.get(), receiver.get(), out);
  // Entered before the loop, completed after it: a killed run stays in the catalog.
  RunCatalogEntry catalog_entry(
      config,
      RunCatalogContext{run_catalog_path(config, options.catalog_path), options.config_path, options.case_name,
                        static_cast<bool>(options.profile_override)},
      report.log_path, meta.start_utime, out);
  if (procedure) print_procedure_header(*procedure, po, out);

  MonotonicClock monotonic;
  VirtualClock virtual_clock;
  LoopClock& clock = simulated_time ? static_cast<LoopClock&>(virtual_clock) : monotonic;
  if (sim != nullptr) sim->set_stall_clock(&clock);  // an overrun fault stalls the loop's own clock

  const auto wall_start = std::chrono::steady_clock::now();
  LoopResult result;
  {
    // A --fast run is not paced, so real-time scheduling would only starve
    // the machine; it is skipped without a warning.
    RealtimeConfig rt = config.loop.realtime;
    rt.enabled = rt.enabled && options.realtime;
    std::optional<RealtimeSession> session;
    if (!simulated_time) {
      session.emplace(rt);
      for (const auto& w : session->warnings()) spdlog::warn("{}", w);
    }
    std::optional<ConsoleStatus> status;
    if (!simulated_time) {
      status.emplace(publisher, meta, rig.driver->layout().input_index(config.controller.feedback),
                     length.unbounded ? std::numeric_limits<double>::infinity() : length.duration_s, out);
    }
    RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, heartbeat, clock, loop_options,
                 rig.safety);
    loop.set_more_channels(rig.more_channels);
    loop.set_event_sink(&events);
    loop.set_operator_commands(commands);
    if (procedure) loop.set_procedure(procedure->runner.get(), procedure->writer.get(), procedure->recovery_every_ticks);
    try {
      result = loop.run(stop);
    } catch (...) {
      stop_services("control loop failed");
      catalog_entry.finish(catalog::EndReason::kFaulted, "control loop failed");
      throw;
    }
  }
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  stop_services("control loop ended, closing the logs");
  result.dropped_records = publisher.dropped();
  report.loop = result;
  report.end_reason = end_reason(result.end_event, meta.layout, *rig.driver);

  print_run_summary(config, options, report, *rig.driver, out);
  if (procedure) print_procedure_summary(*procedure, out);
  print_run_records(report, publisher, events, receiver.get(), foxglove_server.get(), out);
  // A signal's stop is the operator's interruption; a trip that held or
  // stopped the rig made it faulted (rt/loop/rig_loop.cpp finish_run).
  catalog_entry.finish(result.final_state == RigState::kFaulted ? catalog::EndReason::kFaulted
                       : stop.load()                            ? catalog::EndReason::kInterrupted
                                                                : catalog::EndReason::kCompleted,
                       report.end_reason);
  report.catalog_run_id = catalog_entry.id();
  if (!report.csv_path.empty()) {
    const auto csv =
        log_to_csv(report.log_path, report.csv_path, config.telemetry.channel_prefix, options.csv_truth_channels);
    out << "  csv: " << report.csv_path << " (" << csv.rows << " rows)\n";
  }
  out.flush();
  return report;
}

}  // namespace rigctl
