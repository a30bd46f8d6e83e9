// A test procedure in `rigctl run --procedure PROC.yaml [--resume RECOVERY]`:
// the procedure read for the assembled rig, its runner (the loop's demand),
// the recovery writer and, on a resume, the recovery checked against the
// procedure and config and restored (docs/procedures.md).
#pragma once

#include <iosfwd>
#include <memory>
#include <string>

#include "rt/procedure/procedure_runner.hpp"
#include "tools/procedure/procedure_loader.hpp"
#include "tools/procedure/recovery_writer.hpp"

namespace rigctl {

struct ProcedureRunOptions {
  std::string procedure_path;
  std::string resume_path;    // "": a fresh start
  std::string recovery_path;  // where the recovery is written
  std::string config_path;    // its hash goes into the recovery
  std::string case_name;
  bool fast = false;          // --fast: the recovery file in lockstep with the loop
  double period_s = 0.0025;
};

struct ProcedureRun {
  ProcedureSpec spec;
  std::unique_ptr<ProcedureRunner> runner;
  std::unique_ptr<RecoveryWriter> writer;
  int64_t recovery_every_ticks = 0;
  bool resumed = false;
  ProcedureStatus resumed_from;
  std::vector<std::string> rainflow_names;
};

// Throws ConfigError (the procedure) or std::runtime_error (the recovery).
std::unique_ptr<ProcedureRun> open_procedure_run(const ProcedureRunOptions& options, const ChannelLayout& layout,
                                                 int feedback_input);
void print_procedure_header(const ProcedureRun& run, const ProcedureRunOptions& options, std::ostream& out);
void print_procedure_summary(const ProcedureRun& run, std::ostream& out);

}  // namespace rigctl
