// Model-discrepancy diagnosis engine (docs/diagnosis.md sections 4-5):
// baseline output-error fit on the estimation part, screening of every
// candidate effect of the rig (short refits, with a start grid for
// non-convex scalars), full refit of the best few, acceptance on held-out
// gain + parameter significance + parsimony (BIC with N_eff), greedy
// addition, a backward check, and `none` when nothing earns its place.
// Output: the JSON of docs/run-files.md 2.3 and an HTML report.
#pragma once

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/where_result.hpp"

namespace rigctl::diag {

struct ParamValue {
  std::string name;
  std::string unit;
  double value = 0.0;
  double sigma = 0.0;
  bool determined = true;  // false: the run cannot determine it; the JSON writes null and lists it as undetermined
  std::string channel = {};  // the sensor channel it acts on (ParamSpec::channel), or empty
};

// A baseline parameter after the calibration: where it started (the
// nominal), where the fit put it, and whether the run moved it.
struct Calibrated {
  std::string name, unit;
  double nominal = 0.0, value = 0.0, sigma = 0.0;
  double tolerance = 0.0;  // the prior's relative standard deviation (0: no prior)
  bool determined = true;
  bool moved = false;      // by at least half its tolerance
  // A parameter that stands for a cause beyond its band (ParamSpec::stands_for):
  // the cause, and whether the calibration ended at the band's edge (the run
  // asked for more: evidence for that cause, which its candidate must earn).
  std::string stands_for;
  bool at_band_edge = false;
  // A parameter of the loop's I/O timing (ParamSpec::timing) and its bounds.
  bool timing = false;
  double lo = 0.0, hi = 0.0;
};

struct CauseResult {
  std::string cause;
  double confidence = 0.0;
  std::string evidence;
  std::vector<ParamValue> parameters;
  double baseline_fit_percent = 0.0;  // held-out fit of `signal` before this effect was added
  double extended_fit_percent = 0.0;  // ... and with it
  double gain_percent_points = 0.0;
  std::string signal;
  std::vector<std::string> ambiguous_with;  // candidates that explained the residual about as well
  std::string signature;                    // what the residual shows of the effect's signature
  // Whether the cause enters where the baseline's misfit is (where.hpp
  // where_agrees); false flags a cause named at another place.
  bool where_agrees = true;
  // A candidate of several forms (EffectSpec::forms): the one that fitted
  // best, and the estimation cost of each form tried.
  std::string form;
  std::map<std::string, double> form_costs;
  // The sensor channels its parameters showed (ParamSpec::channel): those
  // more than 3 standard deviations from their null.
  std::vector<std::string> channels;
};

struct ScreenedCandidate {
  std::string cause;
  int round = 0;
  double estimation_cost = 0.0;  // after the short screening fit
  bool refitted = false;
  double gain_percent_points = 0.0;  // held-out gain on its best signal (refitted ones)
  std::string signal;
  bool accepted = false;
  std::string reason;  // why it failed (or "accepted")
};

struct Diagnosis {
  std::string rig;
  std::string cause = "none";
  std::vector<CauseResult> causes;
  std::map<std::string, double> baseline_fit_percent;
  std::map<std::string, double> extended_fit_percent;
  std::string validation;
  std::vector<ScreenedCandidate> screened;
  std::vector<ParamValue> baseline_parameters;
  std::vector<ParamValue> final_parameters;  // baseline + kept effects, refitted jointly
  std::map<std::string, double> model_constants;  // RigModel::constants()
  std::vector<Calibrated> calibration;       // the baseline's calibration against its priors
  // The baseline misfits beyond the noise but no candidate earned a validated
  // gain: cause stays none, and the residual is described.
  bool unexplained = false;
  struct Residual {
    std::string signal;
    double rms = 0.0, noise = 0.0;         // held-out residual and the noise floor estimated from the record
    double band_lo_hz = 0.0, band_hi_hz = 0.0, peak_hz = 0.0;  // 10-90 % of its power, and its peak
  };
  Residual unexplained_residual;
  // Where the calibrated baseline misses a signal (docs/diagnosis.md 3).
  WhereResult where;
  std::vector<std::string> stubs;  // cause ids whose candidate is not implemented yet
  double elapsed_s = 0.0;

  // For the report.
  std::vector<double> t;
  std::size_t validation_start = 0;
  std::vector<std::string> output_names;
  std::vector<std::vector<double>> measured, y_baseline, y_extended;
  struct CausePlot {
    std::string cause, indicator_name, signal;
    std::vector<double> indicator, residual, effect_term;
  };
  std::vector<CausePlot> cause_plots;
};

struct DiagnoseOptions {
  double holdout_fraction = 0.2;  // last contiguous block held out
  double min_gain = 1.0;          // g_min [percentage points]
  // g_min for a candidate that takes a misfit beyond the noise down to it
  // (criteria.hpp explains_misfit). A quarter of g_min: the weak 2.1 ms
  // delay of the sweep gains 0.76-0.99 pp on a body LVDT at 99.2 % fit.
  double explained_min_gain = 0.25;
  // A held-out gain this large (and at least strong_se standard errors) is
  // evidence on its own: the parameter-significance test cannot veto it.
  double strong_gain = 3.0;
  double strong_se = 4.0;
  // Two candidates explain the residual about equally when their gains
  // differ by less than this (and a tenth of the larger).
  double ambiguity_margin = 0.5;
  int refit_top = 3;              // K
  int max_effects = 3;
  // Rig health (docs/rig-health.md 3): calibrate the baseline only, no
  // candidate screened, and the parameters that stand for a cause free beyond
  // their band: a window's calibrated leakage resistance is then the rig's
  // whole leakage, trended over windows; whether it changed is the change
  // detector's question over many windows, not one window's gates.
  bool calibration_only = false;
  // Threads of the whole diagnosis, the calling one included (--threads):
  // its nested parallel loops share them (parallel.hpp ThreadBudget).
  int threads = 2;
  std::ostream* progress = nullptr;  // stderr in the program
};

Diagnosis diagnose(const RigModel& model, const DiagnoseOptions& options);

// Contract fit percent, 100 (1 - ||y - y_sim|| / ||y - mean(y)||) over [begin, end).
double fit_percent(const std::vector<double>& y, const std::vector<double>& y_sim, std::size_t begin, std::size_t end);

void write_json(const Diagnosis& d, std::ostream& out);
void write_report(const Diagnosis& d, std::ostream& out);

}  // namespace rigctl::diag
