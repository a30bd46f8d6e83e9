// A Foxglove server fed with rigctl's telemetry: the server and its feed in
// one object, for `rigctl run --ws` (fed by the publisher's tap) and `rigctl
// bridge` (fed from an LCM network). Construct and start() it before the
// real-time set-up, so its thread keeps normal priority.
#pragma once

#include <string>
#include <vector>

#include "foxglove/server/server.hpp"
#include "foxglove/telemetry/telemetry_feed.hpp"

namespace rigctl::foxglove {

class TelemetryServer {
 public:
  // Binds (throws std::runtime_error naming the address and port).
  TelemetryServer(const ServerOptions& options, const std::string& channel_prefix, std::vector<Parameter> parameters);

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
};

}  // namespace rigctl::foxglove
