// `rigctl log2mcap`: a run's LCM log as an MCAP file (tools/runfile/log2mcap.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/runfile/log2mcap.hpp"

namespace rigctl::cli {

namespace {

class Log2McapSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("log2mcap", "Convert a run's LCM log into an MCAP file for Foxglove, Lichtblick and PlotJuggler (docs/foxglove.md)");
    c->add_option("log", log_path_, "LCM log written by rigctl run")->required();
    c->add_option("mcap", mcap_path_, "MCAP file to write")->required();
    c->add_option("--channel-prefix", prefix_, "Telemetry channel prefix used by the run");
    return *c;
  }

  int run(const Invocation& invocation) override {
    const auto result = log_to_mcap(log_path_, mcap_path_, prefix_);
    auto& out = invocation.out;
    out << "log2mcap: " << result.messages << " messages in " << result.chunks << " chunks written to " << mcap_path_;
    if (result.skipped > 0) out << " (" << result.skipped << " events of other channels or undecodable skipped)";
    out << "\n";
    for (const auto& [channel, n] : result.per_channel) out << "  " << channel << ": " << n << "\n";
    if (!result.warning.empty()) invocation.err << "rigctl log2mcap: warning: " << result.warning << "\n";
    return 0;
  }

 private:
  std::string log_path_, mcap_path_, prefix_ = "RIGCTL_";
};

}  // namespace

std::unique_ptr<Subcommand> make_log2mcap_subcommand() { return std::make_unique<Log2McapSubcommand>(); }

}  // namespace rigctl::cli
