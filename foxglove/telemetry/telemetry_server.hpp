// A Foxglove server fed with rigctl's telemetry: the server and its feed in
// one object, for `rigctl run --ws` (fed by the publisher's tap) and `rigctl
// bridge` (fed from an LCM network). Construct and start() it before the
// real-time set-up, so its thread keeps normal priority. It also serves the
// operator console's page at `/` (docs/console.md), which takes commands
// once enable_console_commands() is given the run's command receiver.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "foxglove/console/console_gateway.hpp"

#include "foxglove/server/server.hpp"
#include "foxglove/telemetry/telemetry_feed.hpp"
#include "rt/comms/event_log.hpp"

namespace rigctl::foxglove {

class TelemetryServer {
 public:
  // Binds (throws std::runtime_error naming the address and port).
  TelemetryServer(const ServerOptions& options, const std::string& channel_prefix, std::vector<Parameter> parameters);
  // Stops the server first: its thread may still call the console's gateway.
  ~TelemetryServer() { server_.stop(); }
  TelemetryServer(const TelemetryServer&) = delete;
  TelemetryServer& operator=(const TelemetryServer&) = delete;

  // Before start(): the server's refusals and the console's control
  // changes also go into the run's event log (rate-limited).
  void log_to(EventLog& events);
  // Before start(): the console's commands go to `intake` (operator mode);
  // control held by a console silent for control_timeout_s is released.
  void enable_console_commands(CommandIntake& intake, double control_timeout_s);

  void start() { server_.start(); }
  void stop() { server_.stop(); }
  TelemetryTap& tap() { return feed_; }
  uint16_t port() const { return server_.port(); }
  std::string url() const;  // ws://ADDR:PORT
  ServerStats stats() const { return server_.stats(); }
  // One line per client for a run's report: what it got and what it lost.
  std::string describe_clients() const;

 private:
  Server server_;
  TelemetryFeed feed_;
  std::unique_ptr<ConsoleGateway> console_;
  EventLog* events_ = nullptr;
};

}  // namespace rigctl::foxglove
