#include "tools/procedure/procedure_run.hpp"

#include <cmath>
#include <filesystem>
#include <ostream>

#include "tools/procedure/rainflow_files.hpp"

namespace rigctl {

namespace {

// The recovery at least this often (issue 30: "at least every 10 s"), also
// through holds and long drive passes that end no cycle.
constexpr double kRecoveryEvery_s = 10.0;

std::string config_hash_of(const ProcedureRunOptions& o) {
  if (o.config_path.empty() || !std::filesystem::exists(o.config_path)) return "";
  return text_hash(file_hash(o.config_path) + "#" + o.case_name);
}

// The rainflow matrices beside the recovery file, rewritten when a pass or
// a step has ended (committed cycles plus the residue's halves).
void write_matrices(const ProcedureRecovery& r, const std::vector<std::string>& names, const std::string& base) {
  for (std::size_t i = 0; i < names.size() && i < r.rainflow_channels; ++i) {
    const RainflowResidue& res = r.rainflow[i];
    RainflowChannel ch;
    ch.committed().set_data(res.committed);
    ch.counter().restore(res.points.data(), res.size, res.has_pending, res.pending, res.direction);
    RainflowMatrix m;
    ch.snapshot(m);
    write_rainflow_matrix(base + ".rainflow-" + names[i] + ".csv", names[i], m);
  }
}

}  // namespace

std::unique_ptr<ProcedureRun> open_procedure_run(const ProcedureRunOptions& o, const ChannelLayout& layout,
                                                 int feedback_input) {
  auto run = std::make_unique<ProcedureRun>();
  ProcedureContext ctx;
  ctx.layout = &layout;
  ctx.feedback_input = feedback_input;
  ctx.period_s = o.period_s;
  run->spec = load_procedure_for_run(o.procedure_path, ctx);
  for (int i : run->spec.rainflow_channels) run->rainflow_names.push_back(layout.inputs[static_cast<std::size_t>(i)].name);
  run->runner = std::make_unique<ProcedureRunner>(run->spec, o.period_s, feedback_input);
  const RecoveryIdentity id{o.procedure_path, run->spec.hash, o.config_path, config_hash_of(o)};
  if (!o.resume_path.empty()) {
    const RecoveryFile file = read_recovery_file(o.resume_path);
    check_recovery_identity(file, id, o.resume_path);
    run->runner->restore(file.recovery);
    run->resumed = true;
    run->resumed_from = file.recovery.status;
  }
  // Matrices when a pass or step ended: the writer compares with the last.
  auto last = std::make_shared<ProcedureStatus>(run->resumed_from);
  const auto names = run->rainflow_names;
  const std::string base = o.recovery_path;
  auto on_written = [last, names, base](const ProcedureRecovery& r) {
    if (names.empty()) return;
    const bool boundary = r.status.step != last->step || r.status.pass != last->pass ||
                          r.status.phase == ProcedurePhase::kDone;
    *last = r.status;
    if (boundary) write_matrices(r, names, base);
  };
  run->writer = std::make_unique<RecoveryWriter>(o.recovery_path, id, o.fast, on_written);
  run->recovery_every_ticks = std::llround(kRecoveryEvery_s / o.period_s);
  return run;
}

void print_procedure_header(const ProcedureRun& run, const ProcedureRunOptions& o, std::ostream& out) {
  out << "  procedure: " << o.procedure_path << " (" << run.spec.steps.size() << " steps, "
      << run.spec.programmed_cycles() << " test cycles programmed), recovery " << o.recovery_path << "\n";
  if (run.resumed) {
    const ProcedureStatus& s = run.resumed_from;
    out << "  resumed from " << o.resume_path << ": step " << s.step << " ("
        << run.spec.steps[static_cast<std::size_t>(std::min<int>(s.step, static_cast<int>(run.spec.steps.size()) - 1))].name
        << "), cycle " << s.step_cycles << " of the step, " << s.total_cycles << " test cycles done\n";
  }
  out.flush();
}

void print_procedure_summary(const ProcedureRun& run, std::ostream& out) {
  const ProcedureStatus& s = run.runner->status();
  out << "  procedure: " << (s.phase == ProcedurePhase::kDone ? "finished" : "stopped in step " + std::to_string(s.step))
      << ", " << s.total_cycles << " of " << run.spec.programmed_cycles() << " test cycles, " << s.ramp_in_cycles
      << " ramp-in cycles apart\n";
  if (!run.rainflow_names.empty()) out << "  pseudo-damage (" << run.rainflow_names[0] << "): " << s.damage << "\n";
  out << "  recovery: " << run.writer->path() << " (" << run.writer->files_written() << " writes"
      << (run.writer->error().empty() ? "" : ", FAILED: " + run.writer->error()) << ")\n";
}

}  // namespace rigctl
