// `rigctl bench`: the benchmarks (tools/bench/bench_command.hpp, BENCHMARKS.md).
#include <CLI/CLI.hpp>

#include "tools/bench/bench_command.hpp"
#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"

namespace rigctl::cli {

namespace {

class BenchSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("bench", "Benchmarks: loop timing vs cyclictest, plant speed and accuracy vs a reference integrator, I/O, scaling (BENCHMARKS.md)");
    c->add_flag("--quick", options_.quick, "Seconds instead of minutes: checks that every section runs (rough numbers)");
    c->add_option("--json", options_.json_path, "Write every result to this JSON file");
    c->add_option("--config-dir", options_.config_dir, "Folder with quarter_car.yaml and pneumatic_rotary.yaml (default: config)")->check(CLI::ExistingDirectory);
    c->add_option("--sweep-rig", options_.sweep_rig, "diagnosis_sweep: only this rig kind");
    c->add_option("--sweep-jobs", options_.sweep_jobs, "diagnosis_sweep: runs diagnosed at a time (default 2; 1: each its own wall time)")->check(CLI::Range(1, 8));
    c->add_option("--section", options_.sections, "Run only this section; repeatable")->check(CLI::IsMember(bench_section_names()));
    return *c;
  }

  // The command line goes into the results, so that they say how they were made.
  int run(const Invocation& invocation) override {
    options_.command_line = invocation.command_line;
    return run_bench(options_, stop_on_signals(), invocation.out);
  }

 private:
  BenchOptions options_;
};

}  // namespace

std::unique_ptr<Subcommand> make_bench_subcommand() { return std::make_unique<BenchSubcommand>(); }

}  // namespace rigctl::cli
