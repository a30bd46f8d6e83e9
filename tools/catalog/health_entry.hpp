// What the catalog keeps of a diagnosis (`rigctl diagnose --catalog`, the
// windows of `rigctl health analyse`) and of a health alarm. Plain records:
// the diagnosis layer fills them, the catalog (run layer) stores them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rigctl::catalog {

// A calibrated baseline parameter (role "baseline") or a named cause's
// parameter (role: the cause id).
struct ParameterRecord {
  std::string role;
  std::string name, unit;
  std::optional<double> nominal;  // baseline parameters
  std::optional<double> value;    // empty: undetermined
  std::optional<double> sigma;
  std::optional<double> tolerance;  // the prior's relative standard deviation
  bool determined = true;
  std::string stands_for;  // the cause the parameter stands for (docs/diagnosis.md 4)
};

struct CauseRecord {
  std::string cause, signal;
  double confidence = 0.0, gain_pp = 0.0, baseline_fit_percent = 0.0, extended_fit_percent = 0.0;
};

struct FitRecord {
  std::string signal;
  double baseline_fit_percent = 0.0;
  std::optional<double> extended_fit_percent;
};

struct DiagnosisEntry {
  int64_t id = 0;
  int64_t run_id = 0;
  double window_start_s = 0.0, window_end_s = 0.0;  // rig time within the run [s]
  double time_utc_s = 0.0;                          // the window's start, seconds since the epoch
  std::string rig_name;
  std::string cause = "none";
  bool unexplained = false;
  std::string excitation;  // what the window could not determine, "" when it determined everything
  std::string revision;
  double elapsed_s = 0.0;
  std::vector<ParameterRecord> parameters;
  std::vector<CauseRecord> causes;
  std::vector<FitRecord> fits;
};

struct AlarmEntry {
  int64_t id = 0;
  std::string rig_name;
  std::string parameter;
  std::string stands_for;  // the physical cause it names
  int direction = 0;       // -1: fell, +1: rose
  double size_relative = 0.0;  // the change as a fraction of the reference value
  double size_sigma = 0.0;     // ... in the parameter's standard deviations
  double since_utc_s = 0.0;    // where the change began (the CUSUM's last zero)
  double raised_utc_s = 0.0;   // the point that raised it
  std::optional<int64_t> diagnosis_id;
  std::string message;
};

}  // namespace rigctl::catalog
