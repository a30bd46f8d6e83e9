// `rigctl iterate CONFIG --target TARGET.csv --channel NAME --out DIR
//  [--frf FRF.json | --model DIAGNOSIS.json] [--max-iterations N]
//  [--tolerance PCT]`: the road simulator's drive iteration
// (docs/drive-iteration.md). The rig's FRF from the drive to the target
// channel (measured, or the nominal or a diagnosis's model), its regularised
// inverse, and drives played through the loop until the response matches
// the target. A rig with several control channels is iterated as a
// vector of drives (tools/iterate/mimo_iterate_command.hpp).
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "tools/iterate/drive_iteration.hpp"

namespace rigctl {

struct IterateOptions {
  std::string config_path;
  std::string case_name;
  std::string target_path;  // run file (t, channel) or RPC III (.rsp, .tim)
  std::string channel;      // the rig's channel the target is for, e.g. x_w; several drives: "a_s1,a_s2" (mimo_iterate_command.hpp)
  std::string target_channel;  // the file's channel: a name or a 1-based number (default: `channel`); several: a list as `channel`
  // Longest target played [s]: a drive is one run; ten minutes is well
  // beyond a road simulator's usual block (20-120 s) and keeps the record's
  // FFTs and files small. A longer target is refused, not truncated.
  double max_length_s = 600.0;
  std::string out_dir;
  std::string frf_path;     // FRF file from rigctl identify
  std::string model_path;   // diagnosis JSON: the model it extended
  bool fast = false;        // simulated rigs: simulated time
  bool realtime = true;
  bool plot = false;        // DIR/iterations.png (tools/plots/plot_iteration.py)
  // Hidden effects of the simulated rig (cause, level), as `rigctl make-run`
  // makes them: a rig that differs from its nominal model.
  std::vector<std::pair<std::string, double>> effects;
  IterationSettings settings;
};

struct IterateResult {
  IterationOutcome outcome;
  std::string summary_path;
};

// Throws ConfigError, std::invalid_argument (bad option, channel or file) or
// std::runtime_error (a run or file that cannot be read).
IterateResult run_iterate(const IterateOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
