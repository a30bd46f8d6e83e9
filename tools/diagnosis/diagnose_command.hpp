// `rigctl diagnose` (docs/run-files.md section 2).
#pragma once

#include <ostream>
#include <string>

namespace rigctl {

struct DiagnoseCommandOptions {
  // --rig as given: run_diagnose parses it first (an unknown rig kind is bad
  // input, exit 2, like a bad run file).
  std::string rig;
  std::string data_path;
  std::string config_path;  // optional
  std::string json_path;    // optional
  std::string report_path;  // optional
  bool drop_bad_rows = false;
  int decimate = 0;  // 0: the rig's default
  bool quiet = false;
  // --catalog: the diagnosis goes into the run catalog, linked to the run of
  // --data (entered first when it is not there yet; docs/rig-health.md 2).
  std::string catalog_path;
  std::string rig_name;  // --rig-name: the rig's name there (default: the rig kind)
  int threads = 2;  // --threads: of the whole diagnosis (docs/diagnosis.md 4)
};

// Returns the exit code: 0 with a diagnosis (including `none`), 2 for bad
// input (one-line reason on err), 1 for other failures.
int run_diagnose(const DiagnoseCommandOptions& options, std::ostream& out, std::ostream& err);

}  // namespace rigctl
