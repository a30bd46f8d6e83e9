// `rigctl make-series`: a simulated durability series (tools/health/make_series.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/health/make_series.hpp"

namespace rigctl::cli {

namespace {

class MakeSeriesSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("make-series", "A simulated durability series: blocks of runs of one drawn rig while its leakage and friction grow (rig health tests)");
    c->add_option("--rig", rig_, "Rig kind (drifts: quarter_car)")->capture_default_str();
    c->add_option("--config", options_.config_path, "Rig config (default: config/<rig>.yaml)");
    c->add_option("--case", options_.case_name, "Excitation case (default: the rig's diagnosis case)");
    c->add_option("--out", options_.out_dir, "Folder for block-NNN.csv and series.json")->required();
    c->add_option("--blocks", options_.blocks, "Runs in the series")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--block-hours", options_.block_spacing_h, "Hours between block starts")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--start", options_.start_utc, "Start of the first block (UTC)")->capture_default_str();
    c->add_option("--seed", options_.seed, "Seed of the rig's draw (each block's noise is its own)")->capture_default_str();
    c->add_option("--tolerance", options_.tolerance, "Half-width of the rig's parameter draw")->capture_default_str();
    c->add_option("--leakage-growth", options_.leakage_growth, "Leakage conductance growth over the series, a fraction (0.5: +50 %)")->capture_default_str();
    c->add_option("--friction-growth", options_.friction_growth, "Rod friction growth over the series, a fraction")->capture_default_str();
    c->add_option("--duration", options_.duration_s, "Block length [s] (default: the excitation's)");
    return *c;
  }

  int run(const Invocation& invocation) override {
    options_.rig = parse_kind<RigKind>(rig_);
    health::make_series(options_, invocation.err);
    return 0;
  }

 private:
  health::SeriesOptions options_;
  std::string rig_ = "quarter_car";
};

}  // namespace

std::unique_ptr<Subcommand> make_make_series_subcommand() { return std::make_unique<MakeSeriesSubcommand>(); }

}  // namespace rigctl::cli
