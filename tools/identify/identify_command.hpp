// `rigctl identify CONFIG --out FRF.json`: the loop's frequency response
// measured on the rig (simulated or real) through the same assembly, loop
// and safety machinery as `rigctl run`, with an excitation added to the
// demand about an operating point (docs/frf-files.md).
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include "tools/identify/frf_data.hpp"
#include "tools/identify/frf_matrix_file.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl {

struct IdentifyOptions {
  std::string config_path;
  std::string case_name;
  std::string out_path;    // FRF JSON
  std::string plot_path;   // optional Bode plot (PNG), by tools/plots/plot_frf.py
  std::string log_path;    // the run's LCM log; default: the config's log_dir
  std::string csv_path;    // the run file; default: the FRF path with -run.csv
  bool fast = false;       // simulated rigs: simulated time, as fast as the CPU allows
  bool realtime = true;
  IdentifySettings settings;
};

struct IdentifyResult {
  bool aborted = false;      // a limit tripped: the valve went to null, no FRF was written
  std::string abort_reason;  // the trip, e.g. "limit_tripped: x_r_rate"
  IdentifyPlan plan;
  FrfData frf;
  FrfMatrixData matrix;  // a rig with several control channels: the matrix instead of `frf` (mimo_identify.hpp)
  RunReport run;
};

// The rig's channels by run-file name with their SI units (the plant's
// signals and commands); an unknown name gets an empty unit.
std::vector<FrfChannel> frf_channels(const RigConfig& config, const std::vector<std::string>& names);

// Throws ConfigError for a bad config or settings, std::runtime_error for a
// run or record that cannot be analysed. A config with `channels:` is
// identified as a matrix (tools/identify/mimo_identify.hpp).
IdentifyResult run_identify(const IdentifyOptions& options, const std::atomic<bool>& stop, std::ostream& out);

// Runs tools/plots/plot_frf.py on an FRF (and optionally a tuning) file;
// throws std::runtime_error naming the command when it fails.
void plot_frf(const std::string& frf_path, const std::string& png_path, const std::string& tune_json = "");

}  // namespace rigctl
