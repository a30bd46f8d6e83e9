// `rigctl optimize`: the half car's springs and dampers searched (tools/suspension/optimize_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/suspension/optimize_command.hpp"

namespace rigctl::cli {

namespace {

class OptimizeSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("optimize", "Half car: search springs and dampers within Table 2 (NLopt) for the weighted comfort/handling cost");
    c->add_option("config", options_.config_path, "Half-car config (YAML) with an optimize: section")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:`");
    evaluations_option_ = c->add_option("--evaluations", evaluations_, "Simulation runs of the search (overrides optimize.evaluations)")->check(CLI::PositiveNumber);
    c->add_option("--out", options_.out_path, "JSON file for the optimum (default: <log_dir>/half_car-optimum[-CASE].json)");
    c->add_flag("--quiet{false}", options_.progress, "No progress display on stderr");
    return *c;
  }

  int run(const Invocation& invocation) override {
    if (evaluations_option_->count() > 0) options_.evaluations = evaluations_;
    run_optimize(options_, invocation.out, invocation.err);
    return 0;
  }

 private:
  OptimizeOptions options_;
  int evaluations_ = 0;
  CLI::Option* evaluations_option_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_optimize_subcommand() { return std::make_unique<OptimizeSubcommand>(); }

}  // namespace rigctl::cli
