// `rigctl log2csv`: a run's LCM log as a CSV run file (tools/runfile/log2csv.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/runfile/log2csv.hpp"
#include "tools/runfile/procedure_csv.hpp"

namespace rigctl::cli {

namespace {

class Log2CsvSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("log2csv", "Convert a run's LCM log into a CSV run file (docs/run-files.md)");
    c->add_option("log", log_path_, "LCM log written by rigctl run")->required();
    c->add_option("csv", csv_path_, "CSV file to write")->required();
    c->add_option("--channel-prefix", prefix_, "Telemetry channel prefix used by the run");
    return *c;
  }

  int run(const Invocation& invocation) override {
    const auto result = log_to_csv(log_path_, csv_path_, prefix_);
    invocation.out << "log2csv: " << result.rows << " rows of " << result.rig << " written to " << csv_path_;
    if (result.skipped > 0) invocation.out << " (" << result.skipped << " incomplete ticks skipped)";
    invocation.out << "\n";
    // A procedure's counts beside it (docs/procedures.md).
    const std::string procedure_csv = procedure_csv_path(csv_path_);
    if (const auto rows = procedure_log_to_csv(log_path_, procedure_csv, prefix_); rows > 0)
      invocation.out << "log2csv: " << rows << " procedure rows written to " << procedure_csv << "\n";
    return 0;
  }

 private:
  std::string log_path_, csv_path_, prefix_ = "RIGCTL_";
};

}  // namespace

std::unique_ptr<Subcommand> make_log2csv_subcommand() { return std::make_unique<Log2CsvSubcommand>(); }

}  // namespace rigctl::cli
