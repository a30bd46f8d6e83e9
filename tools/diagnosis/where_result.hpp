// What the "where" of a diagnosis found (docs/diagnosis.md 3, "Where"): at
// which place of the model the calibrated baseline misses a signal, how much
// of the held-out residual that signal explains, and which measured
// features it follows. Made by tools/diagnosis/where.cpp, written by
// report.cpp. A plain result type, so engine.hpp need not know how it is made.
#pragma once

#include <string>
#include <vector>

namespace rigctl::diag {

struct WhereRegressor {
  std::string feature;       // e.g. "sign(v_b)", "p1 - p2", "constant"
  double coefficient = 0.0;  // place unit per feature unit (a sign feature: place unit)
  double share = 0.0;        // of the held-out residual it explains on its own, with the others in
};

struct WherePlace {
  std::string name, unit;
  std::vector<std::string> causes;  // the cause ids that enter here (the model's place map)
  // Of the held-out residual (all outputs, weighted as in the fit): the share
  // the reconstructed signal explains, and the same of the part above the
  // noise floor (1: down to the noise).
  double explained_share = 0.0, share_above_noise = 0.0;
  std::vector<WhereRegressor> regressors;  // strongest first
};

struct WhereResult {
  bool computed = false;     // the rig declares places
  bool significant = false;  // the best place explains enough of a misfit beyond the noise
  std::vector<WherePlace> places;  // best first
  std::string sentence;            // "a force on the body that follows sign(v_b) ...: 71 % of the residual"
  // The reconstructed missing signal at the best place along the record, and
  // the raw values of its strongest regressor (the report's plots).
  std::vector<double> signal;
  std::string feature_name;
  std::vector<double> feature_values;
};

}  // namespace rigctl::diag
