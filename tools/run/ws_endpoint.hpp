// `--ws [ADDR:]PORT` of `rigctl run` and `rigctl bridge`.
#pragma once

#include <optional>
#include <string>

#include "config/rig_config.hpp"
#include "foxglove/server/server.hpp"

namespace rigctl {

struct WsEndpoint {
  std::optional<std::string> address;  // absent: the config's, else loopback
  int port = 0;
};

// "8765", "127.0.0.1:8765", "0.0.0.0:0", "[::1]:8765". Throws
// std::invalid_argument naming the text and what is wrong with it.
WsEndpoint parse_ws_endpoint(const std::string& text);

// The server's settings: the config's `telemetry.websocket` with --ws over
// it; nullopt when neither asks for a server.
std::optional<WebsocketConfig> websocket_settings(const std::optional<WebsocketConfig>& config,
                                                  const std::optional<WsEndpoint>& option);

// The server's options from the settings: address, port, queue, limits,
// origins; pings often enough to tell a silent console within its
// control timeout (a third of it, at most once a second).
foxglove::ServerOptions server_options(const WebsocketConfig& ws);

}  // namespace rigctl
