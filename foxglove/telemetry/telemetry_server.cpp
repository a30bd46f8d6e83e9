#include "foxglove/telemetry/telemetry_server.hpp"

#include <sstream>

#include "foxglove/console/console_assets.hpp"
#include "rt/wall_clock.hpp"

namespace rigctl::foxglove {

TelemetryServer::TelemetryServer(const ServerOptions& options, const std::string& channel_prefix,
                                 std::vector<Parameter> parameters)
    : server_(options), feed_(server_, channel_prefix) {
  server_.set_parameters(std::move(parameters));
  server_.set_http_handler(serve_console_asset);
}

void TelemetryServer::log_to(EventLog& events) {
  events_ = &events;
  server_.set_refusal_handler([&events](const std::string& code, const std::string& text) {
    events.push_note(wall_utime_now(), "client_refused", "foxglove", 0, code + ": " + text);
  });
}

void TelemetryServer::enable_console_commands(CommandIntake& intake, double control_timeout_s) {
  ConsoleOptions o;
  o.control_timeout_s = control_timeout_s;
  if (events_ != nullptr) {
    o.on_event = [events = events_](const std::string& code, const std::string& text) {
      events->push_note(wall_utime_now(), code, "console", 0, text);
    };
  }
  console_ = std::make_unique<ConsoleGateway>(server_.sessions(), intake, o);
}

std::string TelemetryServer::url() const {
  const std::string& a = server_.address();
  const bool v6 = a.find(':') != std::string::npos;
  return "ws://" + (v6 ? "[" + a + "]" : a) + ":" + std::to_string(server_.port());
}

std::string TelemetryServer::describe_clients() const {
  const ServerStats s = stats();
  std::ostringstream os;
  os << s.clients << " client" << (s.clients == 1 ? "" : "s") << ", " << s.sent << " messages sent, " << s.dropped
     << " dropped by slow clients (oldest first)";
  if (!s.refusals.empty()) {
    os << "; refused:";
    for (const auto& [code, n] : s.refusals) os << " " << code << " " << n;
  }
  for (const auto& c : s.per_client) {
    os << "\n    " << c.address << " (" << c.subprotocol << "): " << c.sent << " sent, " << c.dropped << " dropped";
  }
  return os.str();
}

}  // namespace rigctl::foxglove
