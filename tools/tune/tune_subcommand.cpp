// `rigctl tune`: gains from a measured FRF or a relay experiment (tools/tune/tune_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/tune/tune_command.hpp"

namespace rigctl::cli {

namespace {

class TuneSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("tune", "Gains for the rig's controller from a measured FRF (or a relay experiment), with predicted margins and step (docs/frf-files.md)");
    c->add_option("config", options_.config_path, "Rig config (YAML)")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:`");
    c->add_option("--frf", options_.frf_path, "FRF file from rigctl identify")->check(CLI::ExistingFile);
    c->add_option("--method", method_, "frf: loop shaping on the FRF; relay: Astrom-Hagglund relay experiment, Ziegler-Nichols gains")->check(CLI::IsMember({"frf", "relay"}));
    c->add_option("--phase-margin", options_.target.phase_margin_deg, "Target phase margin [deg]")->capture_default_str()->check(CLI::Range(10.0, 89.0));
    bandwidth_option_ = c->add_option("--bandwidth", bandwidth_, "Target crossover frequency [Hz] (default: the stiffest design with 6 dB gain margin and sensitivity peak 2)")->check(CLI::PositiveNumber);
    c->add_flag("--no-feedforward{false}", options_.feedforward, "PI: no velocity feedforward of the demand (by default it is 1 / the measured plant's velocity gain)");
    c->add_option("--out", options_.out_path, "Write the config with the tuned gains (YAML, comments kept)");
    c->add_option("--json", options_.json_path, "Write the design and its predictions (JSON)");
    c->add_option("--plot", options_.plot_path, "Bode plot of the measured plant and the tuned loop (PNG)");
    c->add_option("--evaluate", options_.evaluate_path, "Only measure a run of the config's standard step (rigctl run --csv): overshoot, settling, IAE")->check(CLI::ExistingFile);
    c->add_option("--relay-amplitude", options_.relay.amplitude, "Relay output about the hold command [command unit] (default: a tenth of the output limit)")->check(CLI::PositiveNumber);
    c->add_option("--relay-hysteresis", options_.relay.hysteresis, "Relay hysteresis [feedback unit] (default: 3 x the sensor noise)")->check(CLI::PositiveNumber);
    c->add_option("--relay-duration", options_.relay.duration_s, "Relay time [s]")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--log", options_.relay.log_path, "LCM log of the relay run");
    c->add_flag("--fast", options_.relay.fast, "Relay on a simulated plant: simulated time");
    c->add_flag("--no-realtime{false}", options_.relay.realtime, "Do not try mlockall/SCHED_FIFO");
    return *c;
  }

  int run(const Invocation& invocation) override {
    options_.method = parse_kind<TuneMethod>(method_);
    if (bandwidth_option_->count() > 0) options_.target.crossover_hz = bandwidth_;
    run_tune(options_, stop_on_signals(), invocation.out);
    return 0;
  }

 private:
  TuneOptions options_;
  std::string method_ = "frf";
  double bandwidth_ = 0;
  CLI::Option* bandwidth_option_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_tune_subcommand() { return std::make_unique<TuneSubcommand>(); }

}  // namespace rigctl::cli
