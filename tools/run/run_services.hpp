// The services of one `rigctl run` around its control loop, in one owner:
// the test procedure and its recovery writer, the Foxglove server (with the
// operator console), the telemetry publisher and its run log, the event log,
// the operator's command receiver, the systemd notifier, the driver's I/O
// and the run's catalog entry.
//
// start() starts them in order and remembers each one started; stop() stops
// those in reverse. The order is what the run needs on the way down: the
// recovery writer's last write first, the receiver before the event log (its
// last refusals go in), the publisher before the Foxglove server (its last
// messages still reach the server's feed), the driver last (the valve stays
// safe until then). Every way out stops them: the run's end and a signal's
// stop by stop(), a loop that throws by fail(), any other exception by the
// destructor.
#pragma once

#include "tools/procedure/capture_writer.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "foxglove/telemetry/telemetry_server.hpp"
#include "rt/comms/command_receiver.hpp"
#include "rt/comms/event_log.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "tools/procedure/procedure_run.hpp"
#include "tools/run/loop_heartbeat.hpp"
#include "tools/run/run_catalog.hpp"
#include "tools/run/run_plan.hpp"
#include "tools/run/service_notify.hpp"

namespace rigctl {

class RunServices {
 public:
  // Builds every service, none started: opens the procedure (ConfigError
  // for the procedure, runtime_error for its recovery), binds the Foxglove
  // server, opens the run log and the event log and, in operator mode
  // without the caller's own commands, the command receiver.
  RunServices(const RunOptions& options, RunPlan& plan);
  // Stops what is still running; a catalog entry not finished is finished
  // as faulted ("run failed").
  ~RunServices();
  RunServices(const RunServices&) = delete;
  RunServices& operator=(const RunServices&) = delete;

  // The driver's I/O, the Foxglove server, the publisher, the event log, the
  // command receiver, the systemd notifier, the recovery writer; all before
  // the loop takes real-time priority, so their threads keep normal priority.
  void start();
  // Enters the run into the catalog as running: a killed run stays in it.
  void enter_in_catalog(std::ostream& out);
  // The loop's event sink, operator commands and procedure.
  void attach(RigLoop& loop);
  // Stops what start() started, in reverse; `why` is systemd's STOPPING
  // status. Idempotent.
  void stop(const std::string& why);
  // After stop(): completes the catalog entry from the closed log.
  void finish_in_catalog(catalog::EndReason reason, const std::string& detail);
  // The run failed: stop(why), and the catalog entry finished as faulted.
  void fail(const std::string& why);

  TelemetrySink& loop_telemetry() { return heartbeat_; }  // the publisher, its records counted for systemd
  const TelemetryPublisher& publisher() const { return publisher_; }
  TelemetryPublisher& publisher() { return publisher_; }
  const EventLog& events() const { return events_; }
  const foxglove::TelemetryServer* server() const { return server_.get(); }
  const CommandReceiver* receiver() const { return receiver_.get(); }
  const ProcedureRun* procedure() const { return procedure_.get(); }
  const ProcedureRunOptions& procedure_options() const { return procedure_options_; }
  CaptureWriter* capture() { return capture_.get(); }  // the procedure's data capture, or null
  int64_t catalog_run_id() const { return catalog_ ? catalog_->id() : 0; }

 private:
  // Starts one service and remembers how to stop it.
  void start_one(const std::function<void()>& start, std::function<void(const std::string& why)> stop);
  void open_command_receiver(const RunOptions& options, const RunPlan& plan);

  const RunOptions& options_;
  RunPlan& plan_;
  ProcedureRunOptions procedure_options_;
  std::unique_ptr<ProcedureRun> procedure_;
  // Fed by the publisher: declared before it, so that it outlives the
  // publisher's thread.
  std::unique_ptr<CaptureWriter> capture_;
  std::unique_ptr<foxglove::TelemetryServer> server_;
  TelemetryPublisher publisher_;
  EventLog events_;
  std::unique_ptr<CommandReceiver> receiver_;
  SpscQueue<OperatorCommand>* operator_commands_ = nullptr;
  LoopHeartbeat heartbeat_;  // counts the loop's ticks for the systemd watchdog (a no-op outside systemd)
  ServiceNotifier notifier_;
  std::vector<std::function<void(const std::string& why)>> started_;  // how to stop each, in start order
  std::optional<RunCatalogEntry> catalog_;
  bool catalog_finished_ = false;
};

}  // namespace rigctl
