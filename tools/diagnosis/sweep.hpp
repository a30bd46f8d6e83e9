// The diagnosis sweep: every cause id of a rig (and clean runs) hidden at
// weak and strong levels over several noise seeds by the hidden-effect
// generator, each run diagnosed; the result is a confusion matrix (true cause
// vs the top named cause) and the accuracy. `rigctl bench --section
// diagnosis_sweep` runs it and BENCHMARKS.md records it.
#pragma once

#include <atomic>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace rigctl {

struct SweepOptions {
  std::string rig = "quarter_car";    // a rig kind's name (config/rig_kind.hpp), parsed by run_sweep
  std::string config_path;             // default config/<rig>.yaml
  std::vector<std::string> causes;     // empty: every cause id of the rig
  std::vector<double> levels{0.35, 1.0};
  std::vector<int> seeds{11, 12};     // two seeds: each cause in both physical forms (form = seed % 2)
  // Runs with two effects at the strong level, once per seed; scored by
  // whether both are named (two-effect recall).
  std::vector<std::pair<std::string, std::string>> pairs;
  int clean_runs = 3;                  // runs with nothing hidden (expect "none")
  int threads = 2;
  double duration_s = 0.0;             // 0: the excitation's length
  std::string scratch_dir;             // run files go here
};

struct SweepCell {
  std::string truth, level, named;  // level: "weak", "strong" or "clean"; truth "a+b" for a pair
  double seconds = 0.0;           // making the run and diagnosing it
  double diagnose_seconds = 0.0;  // diagnosing it (the model from the run file, then diagnose())
  double gain = 0.0;  // of the named cause (0 for none)
  std::vector<std::string> all_named;
  bool unexplained = false;
};

struct SweepResult {
  std::vector<std::string> labels;  // "none" then the rig's cause ids
  std::map<std::string, std::map<std::string, int>> confusion;  // truth -> named -> count
  std::vector<SweepCell> cells;
  int correct = 0, total = 0;       // single-effect and clean runs: top cause right
  int jobs = 1;                     // runs made and diagnosed at a time
  int pairs_found = 0, pairs_total = 0;  // two-effect runs: both named
  double wall_s = 0.0;
};

SweepResult run_sweep(const SweepOptions& options, const std::atomic<bool>& stop, std::ostream& progress);

// Markdown table of the confusion matrix with per-row accuracy.
void write_confusion_markdown(const SweepResult& r, std::ostream& out);

}  // namespace rigctl
