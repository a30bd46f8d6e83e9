// `rigctl bench`: measures the loop against cyclictest, the plants against a
// reference integrator, the I/O paths against bare clients, and how costs
// scale, in one run; prints tables as it goes and writes every number to a
// JSON file. BENCHMARKS.md records a full run. Sections are independent
// (tools/bench/sections.hpp): one that cannot run here is skipped with the
// reason, one that fails is recorded as an error and the others still run.
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

namespace rigctl {

struct BenchOptions {
  bool quick = false;                 // seconds instead of minutes: checks that everything runs, numbers are rough
  std::string json_path;              // "" = no JSON file
  std::string config_dir = "config";  // where quarter_car.yaml and pneumatic_rotary.yaml are
  std::vector<std::string> sections;  // run only these (names as bench_section_names()); empty = all
  std::string command_line;           // as typed, for the record
  std::string sweep_rig;              // diagnosis_sweep: only this rig ("" = all three)
  // diagnosis_sweep: runs made and diagnosed at a time. 2 fills the cores
  // sooner; 1 gives each diagnosis the machine, so its wall time is the one
  // a user at the rig waits (docs/diagnosis.md 7, the speed criterion).
  int sweep_jobs = 2;
};

// Section names in the order they run.
std::vector<std::string> bench_section_names();

// Returns the exit code: 0 when every section ran or was skipped with a
// reason, 1 when a section failed (its error is printed and in the JSON).
// Throws std::invalid_argument for an unknown section name.
int run_bench(const BenchOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
