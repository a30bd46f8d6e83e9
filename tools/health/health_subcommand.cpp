// `rigctl health analyse|report`: rig health over long runs
// (tools/health/health_command.hpp, docs/rig-health.md).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/health/health_command.hpp"

namespace rigctl::cli {

namespace {

class HealthSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("health", "Rig health: diagnose long runs in windows, trend the rig's parameters, raise alarms (docs/rig-health.md)");
    c->require_subcommand(1);
    add_analyse(*c);
    add_report(*c);
    return *c;
  }

  int run(const Invocation& invocation) override {
    if (analyse_->parsed()) return health::run_health_analyse(analyse_options_, stop_on_signals(), invocation.out, invocation.err);
    if (report_->parsed()) return health::run_health_report(report_options_, invocation.out, invocation.err);
    return 0;
  }

 private:
  void add_analyse(CLI::App& health) {
    auto& o = analyse_options_;
    analyse_ = health.add_subcommand("analyse", "Calibrate the rig's model in windows of a run (RUN.lcm or RUN.csv) into the catalog");
    analyse_->add_option("record", o.record_path, "LCM log or CSV run file")->required()->check(CLI::ExistingFile);
    analyse_->add_option("--catalog", o.catalog_path, "Run catalog (SQLite)")->required();
    analyse_->add_option("--window", o.window_s, "Window length [s]")->capture_default_str()->check(CLI::PositiveNumber);
    analyse_->add_option("--rig-name", o.rig_name, "The rig's name for a run not yet in the catalog (default: the rig kind)");
    analyse_->add_option("--config", o.config_path, "Rig config: the model's nominal parameters and controller")->check(CLI::ExistingFile);
    analyse_->add_option("--decimate", o.decimate, "Keep every Nth sample (default: the rig's choice)");
    analyse_->add_flag("--full", o.full_diagnosis, "Screen the candidate causes in every window too (the whole diagnosis; slow)");
    analyse_->add_flag("--follow", o.follow, "The LCM log is still being written: analyse windows as they complete, until the run ends");
  }

  void add_report(CLI::App& health) {
    auto& o = report_options_;
    report_ = health.add_subcommand("report", "Parameter trends with uncertainty bands, CUSUM change detection and alarms");
    report_->add_option("--catalog", o.catalog_path, "Run catalog (SQLite)")->required()->check(CLI::ExistingFile);
    report_->add_option("--rig", o.rig_name, "The rig's name in the catalog")->required();
    report_->add_option("--json", o.json_path, "Write the trends and alarms as JSON");
    report_->add_option("--html", o.html_path, "Write a self-contained HTML page with the trends");
    report_->add_option("--png", o.png_path, "Plot the trends (PNG; needs matplotlib: setup.sh --plots)");
    report_->add_option("--reference", o.trends.reference_points, "Windows that set each parameter's reference")->capture_default_str()->check(CLI::PositiveNumber);
    report_->add_option("--cusum-k", o.trends.cusum.k, "CUSUM allowance [sd]")->capture_default_str()->check(CLI::PositiveNumber);
    report_->add_option("--cusum-h", o.trends.cusum.h, "CUSUM threshold [sd]")->capture_default_str()->check(CLI::PositiveNumber);
  }

  health::AnalyseOptions analyse_options_;
  health::ReportOptions report_options_;
  CLI::App* analyse_ = nullptr;
  CLI::App* report_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_health_subcommand() { return std::make_unique<HealthSubcommand>(); }

}  // namespace rigctl::cli
