#include "tools/bridge/bridge_command.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "config/rig_config.hpp"
#include "foxglove/telemetry/telemetry_server.hpp"
#include "tools/run/console_station.hpp"
#include "tools/run/rig_parameters.hpp"

namespace rigctl {

namespace {

// Every message on the bus goes to the feed; it keeps the telemetry channels.
class Forwarder {
 public:
  explicit Forwarder(TelemetryTap& tap) : tap_(tap) {}
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    ++received_;
    tap_.on_message(channel, rbuf->recv_utime, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size);
  }
  int64_t received() const { return received_; }

 private:
  TelemetryTap& tap_;
  int64_t received_ = 0;
};

// How long one wait for LCM traffic lasts: the stop flag is looked at this often.
constexpr int kPollMs = 100;

}  // namespace

int run_bridge(const BridgeOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  if (options.lcm_url.empty()) throw std::runtime_error("bridge: --lcm-url is required (e.g. udpm://239.255.76.67:7667?ttl=1)");
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("bridge: cannot open LCM URL '" + options.lcm_url + "'");

  foxglove::ServerOptions so;
  so.address = options.ws.address.value_or(WebsocketConfig{}.address);
  so.port = static_cast<uint16_t>(options.ws.port);
  so.client_queue_messages = static_cast<std::size_t>(options.client_queue_messages);
  so.name = "rigctl bridge";
  so.metadata = {{"lcm_url", options.lcm_url}};
  std::vector<foxglove::Parameter> parameters;
  if (!options.config_path.empty()) {
    const RigConfig config = load_rig_config(options.config_path);
    parameters = rig_parameters(config);
    so.metadata["rig"] = std::string(to_string(config.rig));
    so.metadata["config"] = options.config_path;
    // The console at `/` watches only here: commands go to the rig's own
    // receiver with `rigctl cmd` (the bridge holds no key).
    so.metadata[foxglove::kStationMetadataKey] = foxglove::station_json(console_station(config, ChannelLayout{}, ""));
  }
  foxglove::TelemetryServer server(so, options.channel_prefix, std::move(parameters));
  Forwarder forwarder(server.tap());
  lcm.subscribe(".*", &Forwarder::handle, &forwarder);
  server.start();
  out << "rigctl bridge: " << options.lcm_url << " channels " << options.channel_prefix << "*\n"
      << "  foxglove: " << server.url() << " serves " << options.channel_prefix
      << "* as JSON (Foxglove, Lichtblick; docs/foxglove.md)\n";
  out.flush();

  const auto start = std::chrono::steady_clock::now();
  auto done = [&] {
    if (stop.load()) return true;
    if (!options.duration_s) return false;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= *options.duration_s;
  };
  while (!done()) {
    // A signal interrupts the wait (EINTR): the loop's condition decides.
    if (lcm.handleTimeout(kPollMs) < 0 && errno != EINTR) {
      throw std::runtime_error("bridge: reading LCM failed on " + options.lcm_url + ": " + std::strerror(errno));
    }
  }
  server.stop();
  out << "  received " << forwarder.received() << " LCM messages\n"
      << "  foxglove: " << server.describe_clients() << "\n";
  return 0;
}

}  // namespace rigctl
