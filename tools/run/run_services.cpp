#include "tools/run/run_services.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <stdexcept>

#include "tools/run/console_station.hpp"
#include "tools/run/operator_mode.hpp"
#include "tools/run/rig_parameters.hpp"
#include "tools/run/ws_endpoint.hpp"

namespace rigctl {

namespace {

ProcedureRunOptions procedure_options_for(const RunOptions& options, const RunPlan& plan) {
  ProcedureRunOptions po;
  if (options.procedure_path.empty()) return po;
  po.procedure_path = options.procedure_path;
  po.resume_path = options.resume_path;
  po.recovery_path = options.recovery_path.empty() ? plan.records.log_path + ".recovery" : options.recovery_path;
  po.config_path = options.config_path;
  po.case_name = options.case_name;
  po.fast = options.fast;
  po.period_s = plan.config.loop.period_s;
  return po;
}

// --procedure: the test procedure read for the assembled rig (and its
// recovery, on --resume); nullptr without one.
std::unique_ptr<ProcedureRun> open_procedure(const ProcedureRunOptions& po, const RunOptions& options, RunPlan& plan) {
  if (po.procedure_path.empty()) {
    if (!options.resume_path.empty()) throw std::runtime_error("--resume continues a procedure: give its --procedure too");
    return nullptr;
  }
  auto procedure = open_procedure_run(po, plan.rig.driver->layout(), std::max(0, plan.rig.safety.feedback_input));
  // The run's header names the steps and the programmed cycles
  // (RIGCTL_PROCEDURE's readers: the console, Foxglove, log2csv).
  TelemetryMeta& meta = plan.records.meta;
  for (const auto& step : procedure->spec.steps) {
    meta.procedure_step_names.push_back(step.name);
    meta.procedure_step_kinds.emplace_back(to_string(step.kind));
  }
  meta.procedure_cycles = procedure->spec.programmed_cycles();
  return procedure;
}

// The procedure's data capture (docs/procedures.md), when its file asks for one.
std::unique_ptr<CaptureWriter> make_capture(const ProcedureRun* procedure, const RunPlan& plan) {
  if (procedure == nullptr || !procedure->spec.capture.enabled) return nullptr;
  return std::make_unique<CaptureWriter>(plan.records.log_path + ".capture", procedure->spec.capture,
                                         plan.rig.driver->layout(), plan.records.meta.procedure_step_names,
                                         plan.config.loop.period_s, plan.config.telemetry.channel_prefix);
}

// The Foxglove server of the run, when the config or --ws asks for one.
// Its page at `/` is the operator console, which takes signed commands in
// operator mode (docs/console.md) when the run's own receiver takes them.
std::unique_ptr<foxglove::TelemetryServer> make_foxglove_server(const RunOptions& options, const RunPlan& plan) {
  const RigConfig& config = plan.config;
  const auto ws = websocket_settings(config.telemetry.websocket, options.websocket);
  if (!ws) return nullptr;
  foxglove::StationDescription station = console_station(config, plan.rig.driver->layout(), plan.rig.setpoint_name,
                                                           plan.rig.more_setpoint_names);
  station.commands = plan.operator_run && options.operator_commands == nullptr;
  foxglove::ServerOptions so = server_options(*ws);
  so.name = "rigctl " + std::string(to_string(config.rig));
  so.metadata = {{"rig", std::string(to_string(config.rig))},
                 {"driver", std::string(to_string(config.driver))},
                 {"config", options.config_path},
                 {foxglove::kStationMetadataKey, foxglove::station_json(station)}};
  return std::make_unique<foxglove::TelemetryServer>(so, config.telemetry.channel_prefix, rig_parameters(config));
}

}  // namespace

RunServices::RunServices(const RunOptions& options, RunPlan& plan)
    : options_(options),
      plan_(plan),
      procedure_options_(procedure_options_for(options, plan)),
      procedure_(open_procedure(procedure_options_, options, plan)),
      capture_(make_capture(procedure_.get(), plan)),
      server_(make_foxglove_server(options, plan)),
      publisher_(plan.records.meta, plan.records.lcm_url, plan.records.log_path, plan.records.queue_capacity),
      // Every state change, trip and command, fsync'd per line.
      events_(plan.records.events_path, EventLogMeta{plan.records.meta.rig, plan.rig.driver->layout(),
                                                      plan.records.meta.start_utime, plan.records.meta.queue_policy}),
      operator_commands_(options.operator_commands),
      heartbeat_(publisher_),
      notifier_(heartbeat_.beats()) {
  if (capture_) publisher_.add_tap(capture_.get());
  for (TelemetryTap* tap : options.telemetry_taps) publisher_.add_tap(tap);
  if (server_) publisher_.add_tap(&server_->tap());
  Driver* driver = plan.rig.driver.get();
  publisher_.set_diagnostics_source([driver] { return driver->diagnostics(); }, std::string(to_string(plan.config.driver)));
  events_.set_failure_handler([this](const std::string& text) {
    spdlog::error("{}", text);
    publisher_.report_event("log_write_failed", text);
  });
  if (server_) server_->log_to(events_);
  if (plan.operator_run && operator_commands_ == nullptr) open_command_receiver(options, plan);
}

// The operator's command receiver on the run's LCM URL, with the unit of the
// setpoint commands (the loop's feedback input); the console's commands go
// to it too.
void RunServices::open_command_receiver(const RunOptions& options, const RunPlan& plan) {
  OperatorModeOptions op = plan.operator_options;
  op.lcm_url = plan.records.lcm_url;
  const auto feedback = static_cast<std::size_t>(std::max(0, plan.rig.safety.feedback_input));
  const auto& inputs = plan.rig.driver->layout().inputs;
  op.setpoint_unit = feedback < inputs.size() ? inputs[feedback].unit : "";
  receiver_ = make_operator_receiver(plan.config, op, events_);
  operator_commands_ = &receiver_->queue();
  if (server_) {
    server_->enable_console_commands(receiver_->intake(),
                                     websocket_settings(plan.config.telemetry.websocket, options.websocket)->control_timeout_s);
  }
}

RunServices::~RunServices() {
  try {
    if (!started_.empty() || (catalog_ && !catalog_finished_)) fail("run failed");
  } catch (const std::exception& e) {
    spdlog::error("stopping the run's services: {}", e.what());  // a destructor must not throw
  }
}

void RunServices::start_one(const std::function<void()>& start, std::function<void(const std::string& why)> stop) {
  start();
  started_.push_back(std::move(stop));
}

void RunServices::start() {
  Driver& driver = *plan_.rig.driver;
  start_one([&] { driver.start(); }, [&](const std::string&) { driver.stop(); });
  if (server_) start_one([this] { server_->start(); }, [this](const std::string&) { server_->stop(); });
  start_one([this] { publisher_.start(); }, [this](const std::string&) { publisher_.stop(); });
  start_one([this] { events_.start(); }, [this](const std::string&) { events_.stop(); });
  if (receiver_) start_one([this] { receiver_->start(); }, [this](const std::string&) { receiver_->stop(); });
  start_one([this] { notifier_.start(); }, [this](const std::string& why) { notifier_.stop(why); });
  if (procedure_) {
    // Its last recovery written first on the way down.
    start_one([this] { procedure_->writer->start(); }, [this](const std::string&) { procedure_->writer->stop(); });
  }
}

void RunServices::enter_in_catalog(std::ostream& out) {
  catalog_.emplace(plan_.config,
                   RunCatalogContext{run_catalog_path(plan_.config, options_.catalog_path), options_.config_path,
                                     options_.case_name, static_cast<bool>(options_.profile_override)},
                   plan_.records.log_path, plan_.records.meta.start_utime, out);
}

void RunServices::attach(RigLoop& loop) {
  loop.set_event_sink(&events_);
  loop.set_operator_commands(operator_commands_);
  if (procedure_) loop.set_procedure(procedure_->runner.get(), procedure_->writer.get(), procedure_->recovery_every_ticks);
}

void RunServices::stop(const std::string& why) {
  while (!started_.empty()) {
    const auto stop_one = std::move(started_.back());
    started_.pop_back();
    stop_one(why);
  }
}

void RunServices::finish_in_catalog(catalog::EndReason reason, const std::string& detail) {
  if (!catalog_ || catalog_finished_) return;
  catalog_finished_ = true;
  catalog_->finish(reason, detail);
}

void RunServices::fail(const std::string& why) {
  stop(why);
  finish_in_catalog(catalog::EndReason::kFaulted, why);
}

}  // namespace rigctl
