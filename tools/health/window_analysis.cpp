#include "tools/health/window_analysis.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "tools/catalog/catalog.hpp"
#include "tools/catalog/run_summary.hpp"
#include "tools/diagnosis/catalog_record.hpp"
#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/runfile/log2csv.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl::health {

namespace {

namespace fs = std::filesystem;

// The samples [begin, end) of a run as a run of their own (time kept: the
// window's rig time within the run).
RunFile window_of(const RunFile& run, std::size_t begin, std::size_t end) {
  RunFile w;
  w.metadata = run.metadata;
  w.header = run.header;
  w.dt = run.dt;
  w.resampled = run.resampled;
  w.t.assign(run.t.begin() + static_cast<std::ptrdiff_t>(begin), run.t.begin() + static_cast<std::ptrdiff_t>(end));
  for (const auto& [name, v] : run.columns)
    w.columns[name].assign(v.begin() + static_cast<std::ptrdiff_t>(begin), v.begin() + static_cast<std::ptrdiff_t>(end));
  return w;
}

// A CSV of the record: the record itself, or its LCM log converted into a
// temporary file that goes with the returned guard.
struct CsvOf {
  std::string path;
  bool temporary = false;
  ~CsvOf() {
    if (temporary) std::remove(path.c_str());
  }
};

void convert(const AnalyseOptions& o, CsvOf& csv) {
  if (!catalog::is_lcm_log(o.record_path)) {
    csv.path = o.record_path;
    return;
  }
  csv.path = (fs::temp_directory_path() / ("rigctl-health-" + std::to_string(::getpid()) + ".csv")).string();
  csv.temporary = true;
  log_to_csv(o.record_path, csv.path, o.channel_prefix, /*simulator_truth=*/false);
}

RunFile read_record(const AnalyseOptions& o, RunFileRig& rig) {
  CsvOf csv;
  convert(o, csv);
  RunFile probe = read_run_file(csv.path, RunFileOptions{{}, {}, false, 2});
  const auto named = probe.meta("rig");
  if (!named) throw RunFileError(o.record_path + ": no '# rig:' line: the rig kind is needed for its model");
  rig = run_file_rig_from_string(*named);
  return read_run_file(csv.path, run_file_columns(rig));
}

std::set<long long> windows_done(catalog::Catalog& c, int64_t run_id) {
  std::set<long long> done;
  for (const auto& d : c.diagnoses(run_id)) done.insert(std::llround(d.window_start_s * 1000.0));
  return done;
}

// Diagnoses the complete windows of `run` not yet in the catalog.
void analyse_windows(const AnalyseOptions& o, RunFileRig rig, const RunFile& run, bool ended,
                     const catalog::RunEntry& entry, catalog::Catalog& c, const std::atomic<bool>& stop,
                     AnalyseResult& result, std::ostream& out) {
  const auto per_window = static_cast<std::size_t>(std::llround(o.window_s / run.dt));
  const auto done = windows_done(c, entry.id);
  const double run_start = catalog::utc_seconds(entry.start_utc);
  for (std::size_t b = 0; b < run.size() && !stop.load(); b += per_window) {
    std::size_t e = std::min(run.size(), b + per_window);
    // A run that has ended lends its remainder a window of its own when it is
    // at least half a window long (a run shorter than the window is one
    // window); a shorter remainder is too short to determine as much.
    if (e - b < per_window && !(ended && 2 * (e - b) >= per_window)) break;
    WindowResult w{run.t[b], run.t[e - 1]};
    if (done.count(std::llround(w.start_s * 1000.0))) continue;
    const RunFile window = window_of(run, b, e);
    diag::RigModelOptions mo;
    mo.config_path = o.config_path;
    mo.decimate = o.decimate;
    const auto model = diag::make_rig_model(rig, window, mo);
    diag::DiagnoseOptions dopt;
    dopt.calibration_only = !o.full_diagnosis;
    const diag::Diagnosis d = diag::diagnose(*model, dopt);
    const auto record = diag::catalog_record(d, {entry.id, w.start_s, w.end_s, run_start + w.start_s, entry.rig_name});
    w.diagnosis_id = c.add_diagnosis(record);
    w.undetermined = record.excitation;
    out << "window " << w.start_s << "-" << w.end_s << " s: diagnosis " << w.diagnosis_id << ", cause " << d.cause
        << " (" << std::llround(d.elapsed_s * 1000.0) << " ms)"
        << (w.undetermined.empty() ? "" : "; could not determine " + w.undetermined + ": not trended for them") << "\n";
    out.flush();
    result.windows.push_back(w);
  }
}

// Whether a log's run has ended: its last state message is stopped or faulted.
bool run_ended(const std::string& log, const std::string& prefix) {
  try {
    const auto e = catalog::summarise_lcm_log(log, prefix).end_reason;
    return e != catalog::EndReason::kKilled && e != catalog::EndReason::kRunning;
  } catch (const std::exception&) {
    return false;  // no sample yet
  }
}

}  // namespace

AnalyseResult analyse_run(const AnalyseOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  if (!(o.window_s > 0.0)) throw std::runtime_error("--window must be positive");
  catalog::Catalog c(o.catalog_path);
  AnalyseResult result;
  for (;;) {
    const bool ended = !o.follow || run_ended(o.record_path, o.channel_prefix);
    RunFileRig rig{};
    const RunFile run = read_record(o, rig);
    // The run's entry: found by its log, or entered now. A followed run still
    // being written is entered (or completed) when it has ended.
    const std::string rig_name = o.rig_name.empty() ? std::string(to_string(rig)) : o.rig_name;
    catalog::RunEntry entry;
    if (auto known = c.run_by_log(fs::absolute(o.record_path).lexically_normal().string())) {
      entry = *known;
    } else {
      entry = diag::catalog_run_of(c, o.record_path, rig_name);
    }
    result.run_id = entry.id;
    analyse_windows(o, rig, run, ended, entry, c, stop, result, out);
    if (ended || stop.load()) break;
    std::this_thread::sleep_for(std::chrono::duration<double>(o.follow_poll_s));
  }
  return result;
}

}  // namespace rigctl::health
