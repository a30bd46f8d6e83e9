#include "tools/run/ws_endpoint.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <stdexcept>


namespace rigctl {

namespace {

int parse_port(const std::string& text, const std::string& whole) {
  int port = -1;
  std::size_t used = 0;
  try {
    port = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (text.empty() || used != text.size() || port < 0 || port > 65535) {
    throw std::invalid_argument("--ws '" + whole + "': the port must be a number 0..65535 (0: any free port)");
  }
  return port;
}

bool is_ip_address(const std::string& a) {
  in6_addr any{};
  return inet_pton(AF_INET, a.c_str(), &any) == 1 || inet_pton(AF_INET6, a.c_str(), &any) == 1;
}

}  // namespace

WsEndpoint parse_ws_endpoint(const std::string& text) {
  WsEndpoint e;
  const auto colon = text.rfind(':');
  if (colon == std::string::npos) {
    e.port = parse_port(text, text);
    return e;
  }
  std::string address = text.substr(0, colon);
  if (address.size() >= 2 && address.front() == '[' && address.back() == ']') address = address.substr(1, address.size() - 2);
  if (!is_ip_address(address)) {
    throw std::invalid_argument("--ws '" + text + "': '" + address + "' is not an IP address (e.g. 127.0.0.1:8765 or [::1]:8765)");
  }
  e.address = address;
  e.port = parse_port(text.substr(colon + 1), text);
  return e;
}

std::optional<WebsocketConfig> websocket_settings(const std::optional<WebsocketConfig>& config,
                                                  const std::optional<WsEndpoint>& option) {
  if (!option) return config;
  WebsocketConfig ws = config.value_or(WebsocketConfig{});
  ws.port = option->port;
  if (option->address) ws.address = *option->address;
  return ws;
}

foxglove::ServerOptions server_options(const WebsocketConfig& ws) {
  foxglove::ServerOptions so;
  so.address = ws.address;
  so.port = static_cast<uint16_t>(ws.port);
  so.client_queue_messages = static_cast<std::size_t>(ws.client_queue_messages);
  so.max_clients = static_cast<std::size_t>(ws.max_clients);
  so.allowed_origins = ws.allowed_origins;
  so.client_timeout_s = ws.client_timeout_s;
  so.ping_interval_s = std::min(1.0, ws.control_timeout_s / 3.0);
  return so;
}

}  // namespace rigctl
