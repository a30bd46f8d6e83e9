// `rigctl optimize`: the half car's suspension design (springs and dampers)
// searched within the bounds of seed 001's Table 2 by a global optimiser of
// NLopt (ISRES with the travel limit as a constraint, or CRS2-LM with it as
// a penalty, the paper's "penalty function technique"), each candidate
// evaluated by a fast closed-loop simulation through the same assembly and
// loop as `rigctl run --fast` (tools/suspension/compare_command.hpp).
//
//   cost = w_comfort Wk/Wk0 + w_tyre T/T0 + w_travel S/S0,  peak |travel| <= limit
//
// Wk: ISO 2631-1 Wk-weighted RMS body acceleration; T, S: RMS tyre
// deflection and suspension travel over both corners; 0: the initial design
// (the config's plant). The search runs in coordinates scaled to [0, 1]
// across each variable's bounds, so springs (1e5 N/m) and dampers (1e3 N s/m)
// weigh alike. The optimum is the best feasible design evaluated, the
// initial design included.
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/suspension/suspension_metrics.hpp"

namespace rigctl {

struct OptimizeOptions {
  std::string config_path;
  std::string case_name;
  std::optional<int> evaluations;  // overrides optimize.evaluations
  std::string out_path;            // default: <telemetry.log_dir>/half_car-optimum[-CASE].json
  bool progress = true;            // the progress display on `progress`
};

struct DesignEvaluation {
  std::vector<double> values;  // physical, in the order of the variables
  double cost = 0.0;
  double wk_rms_acc = 0.0;          // [m/s^2]
  double rms_tyre_deflection = 0.0; // [m]
  double rms_travel = 0.0;          // [m]
  double peak_travel = 0.0;         // [m]
  bool feasible = true;             // peak travel within the limit and the run not faulted
  bool faulted = false;
  SuspensionMetrics metrics;
};

struct OptimizeResult {
  SuspensionOptimizeConfig settings;  // as run (evaluations after the override)
  DesignEvaluation initial, best;
  int evaluations = 0;       // simulation runs by the optimiser (the initial design not counted)
  std::string nlopt_result;  // NLopt's return code, or the exception text
  std::string out_path;
  double elapsed_s = 0.0;
};

// Throws ConfigError (exit 2) or std::runtime_error.
OptimizeResult run_optimize(const OptimizeOptions& options, std::ostream& out, std::ostream& progress);

}  // namespace rigctl
