// `rigctl diagnose`: model-discrepancy diagnosis of a run file (tools/diagnosis/diagnose_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/diagnosis/diagnose_command.hpp"
#include "tools/runfile/run_file_rig.hpp"

namespace rigctl::cli {

namespace {

class DiagnoseSubcommand final : public Subcommand {
 public:
  // The options, in the order `rigctl diagnose --help` lists them.
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("diagnose", "Model-discrepancy diagnosis of a run file (docs/run-files.md, docs/diagnosis.md)");
    c->add_option("--rig", options_.rig, "Rig kind: " + known_kind_names<RunFileRig>())->required();
    c->add_option("--data", options_.data_path, "Run file (CSV)")->required();
    c->add_option("--config", options_.config_path, "Rig config (default: nominal parameters)");
    c->add_option("--json", options_.json_path, "Write the diagnosis as JSON");
    c->add_option("--report", options_.report_path, "Write a self-contained HTML report with plots");
    c->add_flag("--drop-bad-rows", options_.drop_bad_rows, "Drop (and count) rows with bad cells instead of failing");
    c->add_option("--decimate", options_.decimate, "Keep every Nth sample (default: the rig's choice)");
    c->add_flag("--quiet", options_.quiet, "No progress on stderr");
    c->add_option("--catalog", options_.catalog_path, "Also write the diagnosis into this run catalog, linked to the run (docs/rig-health.md)");
    c->add_option("--rig-name", options_.rig_name, "With --catalog: the rig's name for a run not yet entered (default: the rig kind)");
    c->add_option("--threads", options_.threads, "Threads of the whole diagnosis (default 2)")->check(CLI::Range(1, 64));
    return *c;
  }

  int run(const Invocation& invocation) override { return run_diagnose(options_, invocation.out, invocation.err); }

 private:
  DiagnoseCommandOptions options_;
};

}  // namespace

std::unique_ptr<Subcommand> make_diagnose_subcommand() { return std::make_unique<DiagnoseSubcommand>(); }

}  // namespace rigctl::cli
