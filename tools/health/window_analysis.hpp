// `rigctl health analyse`: a long run diagnosed in windows on the
// non-real-time side (docs/rig-health.md 3). Each window's baseline is
// calibrated (tools/diagnosis, calibration only), its parameters with their
// standard deviations go into the catalog linked to the run and the window,
// and a window that cannot determine a parameter says so (the excitation
// check: the posterior no narrower than the prior) and is not trended for it.
#pragma once

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace rigctl::health {

struct AnalyseOptions {
  std::string record_path;   // RUN.lcm or RUN.csv
  std::string catalog_path;  // required
  std::string rig_name;      // the rig's name for a run not in the catalog yet (default: the rig kind)
  std::string config_path;   // the rig's config (the model's nominal; default: nominal parameters)
  double window_s = 60.0;
  int decimate = 0;          // 0: the rig's default
  bool full_diagnosis = false;  // also screen the causes per window (slow: the whole diagnosis per window)
  bool follow = false;       // an LCM log still being written: analyse windows as they complete
  double follow_poll_s = 2.0;
  std::string channel_prefix = "RIGCTL_";
  bool quiet = false;
};

struct WindowResult {
  double start_s = 0.0, end_s = 0.0;
  int64_t diagnosis_id = 0;
  std::string undetermined;  // parameters the window could not determine ("" none)
  bool skipped = false;      // already in the catalog
};

struct AnalyseResult {
  int64_t run_id = 0;
  std::vector<WindowResult> windows;
};

// Throws std::runtime_error (RunFileError for bad input) naming the file.
AnalyseResult analyse_run(const AnalyseOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl::health
