// `rigctl rainflow`: a recorded channel's rainflow count (tools/procedure/rainflow_files.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/procedure/rainflow_files.hpp"

namespace rigctl::cli {

namespace {

class RainflowSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("rainflow", "Rainflow count (ASTM E1049) and pseudo-damage of a recorded run's channel (docs/procedures.md)");
    c->add_option("run", options_.run_path, "Run file (CSV) or a run's LCM log (.lcm)")->required()->check(CLI::ExistingFile);
    c->add_option("--channel", options_.channel, "Column to count, e.g. x_r")->required();
    c->add_option("--matrix", options_.matrix_path, "Write the range-mean matrix as CSV");
    c->add_option("--basquin", options_.basquin_exponent, "Basquin exponent of the pseudo-damage")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--reference-range", options_.reference_range, "Range of unit damage (default: the largest range)")->check(CLI::PositiveNumber);
    return *c;
  }

  int run(const Invocation& invocation) override { return run_rainflow_command(options_, invocation.out); }

 private:
  RainflowFileOptions options_;
};

}  // namespace

std::unique_ptr<Subcommand> make_rainflow_subcommand() { return std::make_unique<RainflowSubcommand>(); }

}  // namespace rigctl::cli
