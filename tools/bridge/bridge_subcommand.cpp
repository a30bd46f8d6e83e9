// `rigctl bridge`: a rig network's LCM telemetry to Foxglove (tools/bridge/bridge_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/bridge/bridge_command.hpp"
#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"

namespace rigctl::cli {

namespace {

class BridgeSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("bridge", "Serve a rig network's LCM telemetry (or lcm-logplayer's) to Foxglove/Lichtblick on a WebSocket (docs/foxglove.md)");
    c->add_option("--lcm-url", options_.lcm_url, "LCM URL of the rig network, e.g. udpm://239.255.76.67:7667?ttl=1")->required();
    c->add_option("--ws", ws_, "[ADDR:]PORT to serve on (default address 127.0.0.1; port 0: any free port)")->required();
    c->add_option("--channel-prefix", options_.channel_prefix, "Telemetry channel prefix of the rig")->capture_default_str();
    c->add_option("--config", options_.config_path, "The rig's config: its gains and limits as read-only parameters")->check(CLI::ExistingFile);
    c->add_option("--client-queue", options_.client_queue_messages, "Messages queued per client before the oldest is dropped")->capture_default_str()->check(CLI::PositiveNumber);
    duration_option_ = c->add_option("--duration", duration_, "Stop after this many seconds (default: at SIGINT/SIGTERM)")->check(CLI::PositiveNumber);
    return *c;
  }

  int run(const Invocation& invocation) override {
    options_.ws = parse_ws_endpoint(ws_);
    if (duration_option_->count() > 0) options_.duration_s = duration_;
    return run_bridge(options_, stop_on_signals(), invocation.out);
  }

 private:
  BridgeOptions options_;
  std::string ws_;
  double duration_ = 0.0;
  CLI::Option* duration_option_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_bridge_subcommand() { return std::make_unique<BridgeSubcommand>(); }

}  // namespace rigctl::cli
