#include "tools/run/run_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "config/config_reader.hpp"
#include "rt/realtime.hpp"
#include "tools/common/stage_text.hpp"
#include "tools/runfile/procedure_csv.hpp"
#include "tools/procedure/capture_writer.hpp"
#include "tools/procedure/procedure_run.hpp"
#include "tools/run/console_status.hpp"
#include "tools/run/operator_mode.hpp"
#include "tools/run/run_plan.hpp"
#include "tools/run/run_services.hpp"
#include "tools/runfile/log2csv.hpp"

namespace rigctl {

namespace {

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

void print_run_header(const RunPlan& plan, const RunOptions& options, const RunServices& services, std::ostream& out) {
  const RigConfig& config = plan.config;
  const RunLength& length = plan.length;
  const auto* server = services.server();
  const auto* receiver = services.receiver();
  out << "rigctl run: " << config.rig << " (" << config.driver << " driver) from " << options.config_path
      << (options.case_name.empty() ? "" : " case " + options.case_name) << ", "
      << (length.unbounded ? std::string("until stopped") : fmt::format("{:g} s", length.duration_s)) << " "
      << (options.fast ? "as fast as possible" : options.lock_step ? "in lock-step with rig-sim" : "paced by the real clock") << "\n"
      << "  telemetry: " << plan.records.lcm_url << " channels " << config.telemetry.channel_prefix << "*, a full queue "
      << (plan.records.meta.queue_policy == QueueFullPolicy::kWait ? "holds the loop back (simulated time: nothing is dropped)"
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

// Where the run's records went, and anything that did not get there.
void print_run_records(const RunReport& report, const RunServices& services, std::ostream& out) {
  const TelemetryPublisher& publisher = services.publisher();
  const auto* receiver = services.receiver();
  const auto* server = services.server();
  if (publisher.queue_waits() > 0) {
    out << "  telemetry queue full " << publisher.queue_waits() << " times: the loop waited for the publisher\n";
  }
  out << "  log: " << report.log_path << "\n";
  const EventLogStats es = services.events().stats();
  out << "  events: " << report.events_path << " (" << es.written << " lines, " << std::setprecision(2)
      << "longest write+fsync " << es.max_fsync_ms << " ms" << (es.pending > 0 ? ", " + std::to_string(es.pending) + " NOT WRITTEN" : "")
      << ")\n";
  if (receiver) out << "  operator commands: " << describe_counters(receiver->counters()) << "\n";
  if (server) out << "  foxglove: " << server->describe_clients() << "\n";
  if (publisher.log_failures() > 0) out << "  run log write failures: " << publisher.log_failures() << "\n";
}

// The control loop on the assembled rig, paced by the real clock (with
// real-time scheduling and the console's status line) or in simulated time,
// until its length, a trip that ends it, the operator's end or `stop`.
LoopResult run_loop(RunPlan& plan, const RunOptions& options, RunServices& services, const std::atomic<bool>& stop,
                    std::ostream& out) {
  const RigConfig& config = plan.config;
  // A --fast run is not paced, so real-time scheduling would only starve
  // the machine; it is skipped without a warning.
  RealtimeConfig rt = config.loop.realtime;
  rt.enabled = rt.enabled && options.realtime;
  std::optional<RealtimeSession> session;
  std::optional<ConsoleStatus> status;
  if (!plan.simulated_time) {
    session.emplace(rt);
    for (const auto& w : session->warnings()) spdlog::warn("{}", w);
    status.emplace(services.publisher(), plan.records.meta, plan.rig.driver->layout().input_index(config.controller.feedback),
                   plan.length.unbounded ? std::numeric_limits<double>::infinity() : plan.length.duration_s, out);
  }
  RigLoop loop(*plan.rig.driver, *plan.rig.controller, *plan.rig.profile, plan.rig.detectors, services.loop_telemetry(),
               plan.clock(), plan.loop, plan.rig.safety);
  loop.set_more_channels(plan.rig.more_channels);
  services.attach(loop);
  return loop.run(stop);
}

// The procedure's data capture, finished once the publisher has stopped
// (nothing more comes).
void print_capture_summary(RunServices& services, std::ostream& out) {
  CaptureWriter* capture = services.capture();
  if (capture == nullptr) return;
  capture->finish();
  out << "  capture: " << capture->folder() << " (" << capture->cycles_written() << " cycles' peaks, "
      << capture->histories_written() << " cycle histories, " << capture->trips_written() << " trip windows)\n";
}

// A signal's stop is the operator's interruption; a trip that held or
// stopped the rig made it faulted (rt/loop/rig_loop.cpp finish_run).
catalog::EndReason catalog_end_reason(const LoopResult& result, const std::atomic<bool>& stop) {
  if (result.final_state == RigState::kFaulted) return catalog::EndReason::kFaulted;
  return stop.load() ? catalog::EndReason::kInterrupted : catalog::EndReason::kCompleted;
}

}  // namespace

RunReport run_rig(const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  return run_rig(load_rig_config(options.config_path, options.case_name), options, stop, out);
}

RunReport run_rig(const RigConfig& config_file, const RunOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  RunPlan plan(config_file, options);
  RunServices services(options, plan);
  services.start();
  print_run_header(plan, options, services, out);
  services.enter_in_catalog(out);
  if (services.procedure()) print_procedure_header(*services.procedure(), services.procedure_options(), out);

  RunReport report;
  report.log_path = plan.records.log_path;
  report.events_path = plan.records.events_path;
  report.csv_path = options.csv_path;
  const auto wall_start = std::chrono::steady_clock::now();
  try {
    report.loop = run_loop(plan, options, services, stop, out);
  } catch (...) {
    services.fail("control loop failed");
    throw;
  }
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  services.stop("control loop ended, closing the logs");
  report.loop.dropped_records = services.publisher().dropped();
  report.end_reason = end_reason(report.loop.end_event, plan.records.meta.layout, *plan.rig.driver);

  print_run_summary(plan.config, options, report, *plan.rig.driver, out);
  if (services.procedure()) print_procedure_summary(*services.procedure(), out);
  print_capture_summary(services, out);
  print_run_records(report, services, out);
  services.finish_in_catalog(catalog_end_reason(report.loop, stop), report.end_reason);
  report.catalog_run_id = services.catalog_run_id();
  if (!report.csv_path.empty()) {
    const auto csv = log_to_csv(report.log_path, report.csv_path, plan.config.telemetry.channel_prefix, options.csv_truth_channels);
    out << "  csv: " << report.csv_path << " (" << csv.rows << " rows)\n";
    if (services.procedure()) {
      const std::string proc_csv = procedure_csv_path(report.csv_path);
      const auto rows = procedure_log_to_csv(report.log_path, proc_csv, plan.config.telemetry.channel_prefix);
      out << "  procedure csv: " << proc_csv << " (" << rows << " rows)\n";
    }
  }
  out.flush();
  return report;
}

}  // namespace rigctl
