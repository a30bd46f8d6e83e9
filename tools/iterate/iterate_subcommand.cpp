// `rigctl iterate`: the road simulator's drive iteration (tools/iterate/iterate_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/hidden_effects/effect_texts.hpp"
#include "tools/iterate/iterate_command.hpp"
#include "tools/iterate/test_window.hpp"

namespace rigctl::cli {

namespace {

class IterateSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("iterate", "Iterate the rig's drive until a channel's response matches a target (road simulator; docs/drive-iteration.md)");
    auto& st = options_.settings;
    c->add_option("config", options_.config_path, "Rig config (YAML)")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:`");
    c->add_option("--target", options_.target_path, "Target: a run file (t and the channel) or an RPC III file (.rsp, .tim)")->required()->check(CLI::ExistingFile);
    c->add_option("--channel", options_.channel, "The rig's channel the target is for, e.g. x_w")->required();
    c->add_option("--target-channel", options_.target_channel, "The target file's channel: a name or a 1-based number (default: --channel)");
    c->add_option("--max-length", options_.max_length_s, "Longest target played [s]; a longer one is refused")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--window", window_, "T0:T1, the part of the target the error is judged on [s] (default: where it departs from its lead-in and lead-out)");
    c->add_option("--first-level", st.first_level, "The first drive's level in the band, a share of the inverse's")->capture_default_str()->check(CLI::Range(0.05, 1.0));
    c->add_option("--max-growth", st.max_growth, "Refuse a drive whose content in the band grew more than this over the last one")->capture_default_str()->check(CLI::Range(1.0, 100.0));
    c->add_option("--out", options_.out_dir, "Folder for summary.json and each iteration's drive and response")->required();
    auto* frf = c->add_option("--frf", options_.frf_path, "FRF file from rigctl identify (with the channel: identify --response NAME)")->check(CLI::ExistingFile);
    c->add_option("--model", options_.model_path, "Diagnosis JSON (rigctl diagnose --json): the inverse from the model it extended (default: the config's nominal model)")->check(CLI::ExistingFile)->excludes(frf);
    c->add_option("--max-iterations", st.max_iterations, "Drives played at most")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--tolerance", st.tolerance_percent, "Stop at this relative RMS error [%] over the band")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--gain", st.initial_gain, "The update's gain alpha at the start, 0..1")->capture_default_str()->check(CLI::Range(0.05, 1.0));
    c->add_option("--band", st.inverse.band_min_hz, "Low end of the band [Hz]")->capture_default_str();
    c->add_option("--band-max", st.inverse.band_max_hz, "High end of the band [Hz]")->capture_default_str();
    c->add_flag("--scale", st.scale_to_fit, "Scale a drive beyond the rig's limits until it fits, instead of refusing it");
    c->add_flag("--fast", options_.fast, "Simulated plant only: simulated time, as fast as the CPU allows");
    c->add_flag("--no-realtime{false}", options_.realtime, "Do not try mlockall/SCHED_FIFO");
    c->add_flag("--plot", options_.plot, "Also plot target, responses and errors per iteration (DIR/iterations.png; needs matplotlib)");
    c->add_option("--effect", effect_texts_, "Simulated rig only: a hidden effect, CAUSE[:weak|strong|LEVEL] as for make-run; repeatable");
    return *c;
  }

  // Exit 3: a run of the iteration ended early (a trip or a signal).
  int run(const Invocation& invocation) override {
    options_.effects = parse_effect_texts(effect_texts_);
    if (!window_.empty()) options_.settings.window_s = parse_time_window(window_);
    const auto result = run_iterate(options_, stop_on_signals(), invocation.out);
    return result.outcome.end == IterationEnd::kRunEnded ? 3 : 0;
  }

 private:
  IterateOptions options_;
  std::string window_;
  std::vector<std::string> effect_texts_;
};

}  // namespace

std::unique_ptr<Subcommand> make_iterate_subcommand() { return std::make_unique<IterateSubcommand>(); }

}  // namespace rigctl::cli
