#include "tools/diagnosis/sweep.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <mutex>
#include <sstream>
#include <thread>

#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/parallel.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

struct Job {
  std::string truth;  // cause id or "none"
  double level = 0.0;
  int seed = 1;
  std::string second;  // a second effect (pairs), else empty
};

std::string level_name(double level) {
  if (level == 0.0) return "clean";
  if (level == weak_level()) return "weak";
  if (level == 1.0) return "strong";
  std::ostringstream s;
  s << level;
  return s.str();
}

}  // namespace

SweepResult run_sweep(const SweepOptions& o, const std::atomic<bool>& stop, std::ostream& progress) {
  const RigKind rig = parse_kind<RigKind>(o.rig);
  const RigEffectGenerator& gen = effect_generator(rig);
  SweepResult r;
  r.labels.push_back("none");
  for (const auto& c : gen.causes) r.labels.push_back(c);
  std::vector<Job> jobs;
  for (int k = 0; k < o.clean_runs; ++k) jobs.push_back({"none", 0.0, 100 + k, {}});
  for (const auto& c : o.causes.empty() ? gen.causes : o.causes)
    for (double level : o.levels)
      for (int seed : o.seeds) jobs.push_back({c, level, seed, {}});
  for (const auto& [a, b] : o.pairs)
    for (int seed : o.seeds) jobs.push_back({a, 1.0, seed, b});

  const std::string dir = o.scratch_dir.empty()
                              ? (std::filesystem::temp_directory_path() / ("rigctl_sweep_" + std::to_string(getpid())))
                                    .string()
                              : o.scratch_dir;
  std::filesystem::create_directories(dir);
  std::mutex m;
  std::size_t next = 0, done = 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (;;) {
      std::size_t i;
      {
        std::lock_guard<std::mutex> lock(m);
        if (next >= jobs.size() || stop.load()) return;
        i = next++;
      }
      const Job& j = jobs[i];
      SweepCell cell;
      cell.truth = j.second.empty() ? j.truth : j.truth + "+" + j.second;
      cell.level = level_name(j.level);
      cell.named = "error";
      const auto start = std::chrono::steady_clock::now();
      try {
        MakeRunOptions mr;
        mr.rig = rig;
        mr.config_path = o.config_path;
        if (j.truth != "none") mr.effects.emplace_back(j.truth, j.level);
        if (!j.second.empty()) mr.effects.emplace_back(j.second, j.level);
        mr.seed = j.seed;
        mr.duration_s = o.duration_s;
        mr.out_csv = dir + "/run-" + std::to_string(i) + ".csv";
        std::ostringstream quiet;
        make_run(mr, quiet);
        const auto d_start = std::chrono::steady_clock::now();
        const auto file_rig = run_file_rig(rig);
        if (!file_rig) throw std::runtime_error("the diagnosis has no model of the " + o.rig + " rig");
        const auto rf = read_run_file(mr.out_csv, run_file_columns(*file_rig));
        const auto model = diag::make_rig_model(*file_rig, rf, {});
        // The runs diagnosed at a time share the machine's threads: each
        // diagnosis gets its share, so the sweep never runs more threads
        // than the cores a diagnosis is sized for.
        diag::DiagnoseOptions dopt;
        dopt.threads = std::max(1, static_cast<int>(diag::kDefaultDiagnosisThreads) / std::max(1, o.threads));
        const auto d = diag::diagnose(*model, dopt);
        cell.diagnose_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - d_start).count();
        cell.named = d.cause;
        if (!d.causes.empty()) cell.gain = d.causes.front().gain_percent_points;
        for (const auto& c : d.causes) cell.all_named.push_back(c.cause);
        cell.unexplained = d.unexplained;
        std::filesystem::remove(mr.out_csv);
      } catch (const std::exception& e) {
        cell.named = "error";
        progress << "  " << j.truth << " " << level_name(j.level) << " seed " << j.seed << ": " << e.what() << "\n";
      }
      cell.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::lock_guard<std::mutex> lock(m);
      r.cells.push_back(cell);
      ++done;
      std::string named;
      for (const auto& c : cell.all_named) named += (named.empty() ? "" : "+") + c;
      progress << "  [" << done << "/" << jobs.size() << "] " << cell.truth << " (" << cell.level << ", seed "
               << j.seed << ") -> " << (named.empty() ? cell.named : named)
               << (cell.unexplained ? " (unexplained)" : "") << (cell.named == cell.truth ? "" : "   <-- differs")
               << "  " << std::fixed << std::setprecision(1) << cell.seconds << " s (diagnosis "
               << cell.diagnose_seconds << " s)\n";
      progress.flush();
    }
  };
  std::vector<std::thread> pool;
  r.jobs = std::max(1, o.threads);
  for (int k = 0; k < r.jobs; ++k) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (o.scratch_dir.empty()) std::filesystem::remove_all(dir);
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto& c : r.cells) {
    const auto plus = c.truth.find('+');
    if (plus != std::string::npos) {
      const std::string a = c.truth.substr(0, plus), b = c.truth.substr(plus + 1);
      const auto has = [&](const std::string& x) {
        return std::find(c.all_named.begin(), c.all_named.end(), x) != c.all_named.end();
      };
      ++r.pairs_total;
      if (has(a) && has(b)) ++r.pairs_found;
      continue;
    }
    ++r.confusion[c.truth][c.named];
    ++r.total;
    if (c.named == c.truth) ++r.correct;
  }
  return r;
}

void write_confusion_markdown(const SweepResult& r, std::ostream& out) {
  std::vector<std::string> cols = r.labels;
  bool errors = false;
  for (const auto& [t, row] : r.confusion)
    if (row.count("error")) errors = true;
  if (errors) cols.push_back("error");
  out << "| true \\ named |";
  for (const auto& c : cols) out << " " << c << " |";
  out << " accuracy |\n|---|";
  for (std::size_t i = 0; i < cols.size(); ++i) out << "---:|";
  out << "---:|\n";
  for (const auto& t : r.labels) {
    const auto it = r.confusion.find(t);
    if (it == r.confusion.end()) continue;
    int n = 0;
    for (const auto& [named, k] : it->second) n += k;
    out << "| " << t << " |";
    for (const auto& c : cols) {
      const auto k = it->second.count(c) ? it->second.at(c) : 0;
      out << " " << (k ? (c == t ? "**" + std::to_string(k) + "**" : std::to_string(k)) : "") << " |";
    }
    const int ok = it->second.count(t) ? it->second.at(t) : 0;
    out << " " << ok << "/" << n << " |\n";
  }
  out << "\nAccuracy " << r.correct << "/" << r.total << " (" << std::fixed << std::setprecision(1)
      << (r.total ? 100.0 * r.correct / r.total : 0.0) << " %)";
  if (r.pairs_total > 0) {
    out << "; two-effect runs with both named " << r.pairs_found << "/" << r.pairs_total << ":";
    for (const auto& c : r.cells)
      if (c.truth.find('+') != std::string::npos) {
        std::string named;
        for (const auto& x : c.all_named) named += (named.empty() ? "" : "+") + x;
        out << " " << c.truth << " -> " << (named.empty() ? "none" : named) << ";";
      }
  }
  out << " " << std::setprecision(0) << r.wall_s << " s wall.\n";
  std::vector<double> t;
  for (const auto& c : r.cells) t.push_back(c.diagnose_seconds);
  if (!t.empty()) {
    std::sort(t.begin(), t.end());
    const double median = t.size() % 2 ? t[t.size() / 2] : 0.5 * (t[t.size() / 2 - 1] + t[t.size() / 2]);
    out << "Diagnosis wall time per run: median " << std::setprecision(1) << median << " s, worst " << t.back()
        << " s (" << r.jobs << " at a time).\n";
  }
}

}  // namespace rigctl
