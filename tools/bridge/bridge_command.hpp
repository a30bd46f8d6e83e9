// `rigctl bridge`: the Foxglove WebSocket server for a PC that is not the
// controller. It listens to a rig network's LCM (the rig PC's udpm://, or
// lcm-logplayer replaying a run) and serves the same channels, schemas and
// statuses as `rigctl run --ws` (docs/foxglove.md).
#pragma once

#include <atomic>
#include <optional>
#include <ostream>
#include <string>

#include "tools/run/ws_endpoint.hpp"

namespace rigctl {

struct BridgeOptions {
  std::string lcm_url;                     // e.g. udpm://239.255.76.67:7667?ttl=1
  WsEndpoint ws;                           // --ws [ADDR:]PORT
  std::string channel_prefix = "RIGCTL_";
  std::string config_path;                 // optional: the rig's config, for its gains and limits as parameters
  std::optional<double> duration_s;        // default: until SIGINT/SIGTERM
  int client_queue_messages = WebsocketConfig{}.client_queue_messages;
};

// Returns the exit status; throws std::runtime_error (LCM URL, address in
// use) or ConfigError (the --config file) with a clear message.
int run_bridge(const BridgeOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
