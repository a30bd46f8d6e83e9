// `rigctl compare`: the half car's controllers side by side (tools/suspension/compare_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/suspension/compare_command.hpp"

namespace rigctl::cli {

namespace {

class CompareSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("compare", "Half car: passive, fuzzy, skyhook and LQR on the configured road, metrics beside the paper's");
    c->add_option("config", options_.config_path, "Half-car config (YAML), e.g. config/half_car.yaml")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:` (e.g. iso_c)");
    c->add_option("--out", options_.out_dir, "Folder for the CSV run files and metrics.json (default: <log_dir>/half_car-compare[-CASE])");
    return *c;
  }

  int run(const Invocation& invocation) override {
    run_compare(options_, invocation.out);
    return 0;
  }

 private:
  CompareOptions options_;
};

}  // namespace

std::unique_ptr<Subcommand> make_compare_subcommand() { return std::make_unique<CompareSubcommand>(); }

}  // namespace rigctl::cli
