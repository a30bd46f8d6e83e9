// Model-discrepancy diagnosis: the interface between the engine
// (tools/diagnosis/engine.*) and one rig's sub-model (tools/diagnosis/rigs.cpp).
//
// A rig model holds the measured run and replays it: its simulate() takes
// one flat parameter vector (the baseline's parameters, then every candidate
// effect's parameters) and writes the free-run outputs. Each effect's
// parameters have null values at which the effect vanishes, so the baseline
// is the full vector with every effect at its null, and a candidate is the
// baseline with that effect's parameters freed (docs/diagnosis.md 1).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tools/runfile/run_file.hpp"

namespace rigctl::diag {

struct ParamSpec {
  std::string name;
  std::string unit;
  double init = 0.0;   // start of the fit (the null value for an effect's strength)
  double lo = -1e30;   // physical bounds
  double hi = 1e30;
  double scale = 1.0;  // typical magnitude, for the optimiser's conditioning
  double null = 0.0;   // value at which the effect vanishes (unused for baseline parameters)
  std::vector<double> starts;  // extra start values for a non-convex scalar (grid in the screening)
  bool strength = false;       // the significance test of the effect uses this parameter
  // Baseline parameters a real rig is uncertain about: the stated tolerance,
  // the prior's standard deviation as a fraction of `init` (the nominal). The
  // fit is regularised toward the nominal by it, so a parameter the run does
  // not excite stays put and is reported as undetermined. 0: no prior.
  double prior = 0.0;
  // A baseline parameter whose departure far beyond its tolerance is itself a
  // cause of the list: the leakage resistance of a worn seal, the bulk
  // modulus of aerated oil. `stands_for` is that cause, `toward` the side
  // (-1: below nominal, +1: above). The calibration keeps such a parameter
  // within kCauseBandTolerances of its tolerance on that side (the rule is
  // in workspace.cpp, docs/diagnosis.md 4), so what lies beyond is the
  // cause's candidate to earn through the gates. Empty: an ordinary one.
  std::string stands_for;
  int toward = 0;
  // The sensor channel (run-file column) an effect's parameter acts on, e.g.
  // one sensor's delay: the JSON names the channels whose parameter the run
  // showed (ParamValue::channel). Empty: none in particular.
  std::string channel;
  // The index of the effect's form (EffectSpec::forms), carried in the
  // parameter vector but never fitted: the engine refits the effect in each
  // form and keeps the one that fits best.
  bool form = false;
  // A baseline parameter of the loop's I/O timing (when the sample is taken,
  // when the command takes effect): calibrated within its bounds, reported
  // as the run's `loop_timing`, never a cause (docs/diagnosis.md 4).
  bool timing = false;
};

// How far (in tolerances) a parameter that stands for a cause may calibrate
// toward it. Two: a rig's drawn or real spread is about one tolerance (the
// generator draws within +-5 %, half of R_l's 10 % and one of beta's 5 %),
// while the weakest leak and air of the generator need several (R_l -40 %
// and more, beta -25 % and more, docs/diagnosis.md 4).
constexpr double kCauseBandTolerances = 2.0;

struct EffectSpec {
  std::string cause;  // contract cause id
  std::vector<ParamSpec> params;
  std::string description;
  // The physical forms the candidate can take (a pure delay, a Bessel
  // filter, ...), by the value of its `form` parameter; empty: one form.
  std::vector<std::string> forms = {};
  bool stub = false;  // true: the candidate exists but cannot change the model yet (reported as such)
};

// One output channel scored by fit percent.
struct Output {
  std::string name;  // run-file column, e.g. "x_b"
  std::vector<double> measured;
};

class RigModel {
 public:
  virtual ~RigModel() = default;
  virtual RunFileRig rig() const = 0;
  virtual const std::vector<Output>& outputs() const = 0;
  virtual const std::vector<double>& time() const = 0;
  virtual std::vector<ParamSpec> baseline() const = 0;
  virtual std::vector<EffectSpec> effects() const = 0;
  // theta: baseline parameters then every effect's, in effects() order.
  // y: one vector per output, each time().size() long.
  virtual void simulate(const std::vector<double>& theta, std::vector<std::vector<double>>& y) const = 0;
  // The same replay over the first `samples` samples only; the rest of each
  // output is left unspecified. A fit scores only the estimation part (the
  // first 80 % of the record), so its replays can stop there: the replays
  // are causal, so those samples are the same as the whole record's. The
  // default replays the whole record.
  virtual void simulate_prefix(const std::vector<double>& theta, std::vector<std::vector<double>>& y,
                               std::size_t /*samples*/) const {
    simulate(theta, y);
  }
  // Whether baseline parameter `index` can change the outputs an effect of
  // `cause` acts on: the screening frees only those (a rig of sub-models
  // screens a sub-model's effect without replaying the others).
  virtual bool couples(std::size_t /*index*/, const std::string& /*cause*/) const { return true; }
  // The outputs an effect of `cause` can change (a rig of sub-models: its
  // sub-model's). The parsimony test (BIC) of its candidate is judged on
  // them. Empty: every output.
  virtual std::vector<std::size_t> acts_on(const std::string& /*cause*/) const { return {}; }
  // Fixed values the candidates' laws are written around, by name [SI]: a
  // tool that maps the fitted parameters onto a plant needs them (the quarter
  // car's seal level F_m is at the run's mean pressure sum P_m). JSON
  // `model_constants`.
  virtual std::map<std::string, double> constants() const { return {}; }
  // How the sub-model is replayed (goes into the JSON `validation` string).
  virtual std::string replay() const = 0;
  // Samples at the start that no model can match (state initialisation).
  virtual std::size_t init_window() const { return 20; }
  // Indicator variable of a cause for the report and the evidence features,
  // e.g. body velocity for bearing friction. Empty name: none.
  struct Indicator {
    std::string name;
    std::vector<double> values;
  };
  virtual Indicator indicator(const std::string& cause) const = 0;
  // Where an effect can enter the model (docs/diagnosis.md 3, "Where"):
  // a force on a body, a flow into a chamber, an error on a sensor. The
  // engine reconstructs, at each place, the missing signal the calibrated
  // baseline lacks (tools/diagnosis/where.*). `output` >= 0 with `in_loop`
  // false: an error added to that output after the replay (the engine does
  // it); otherwise the model adds the signal in simulate_with_input.
  // `causes`: the cause ids whose effect enters here (the place map).
  struct Place {
    std::string name, unit;
    double scale = 1.0;  // a typical size of the signal there (the linearisation's step)
    int output = -1;
    bool in_loop = false;
    std::vector<std::string> causes;
  };
  virtual std::vector<Place> places() const { return {}; }
  // The replay with the signal d (one value per sample, held over the
  // period) added at place `place`. Only for places the model adds itself.
  virtual void simulate_with_input(const std::vector<double>& theta, std::size_t /*place*/,
                                   const std::vector<double>& /*d*/, std::vector<std::vector<double>>& y) const {
    simulate(theta, y);
  }
  // Measured signals a missing signal may be a function of (the feature
  // library of the "where"), each with how it enters the library.
  // A velocity enters by its sign and value, a command by its value and its
  // part near null, a position by its value and the travel since its last
  // reversal (raw and saturating: hysteresis), a value as it is.
  enum class FeatureKind { kVelocity, kValue, kCommand, kPosition };
  struct Feature {
    std::string name;
    FeatureKind kind = FeatureKind::kValue;
    std::vector<double> values;
    // The outputs it is measured from: at a sensor's place the engine leaves
    // out the features of that sensor's own measurement (error = measured -
    // replay would fit its residual exactly, anywhere).
    std::vector<int> from;
  };
  virtual std::vector<Feature> features() const { return {}; }
  // The force (or other) term an effect adds, at parameters theta, along the
  // record; for the report's "effect curve vs indicator" plot. May be empty.
  virtual std::vector<double> effect_term(const std::string& /*cause*/, const std::vector<double>& /*theta*/) const {
    return {};
  }
};

struct RigModelOptions {
  std::string config_path;  // --config, may be empty (nominal parameters)
  int decimate = 0;         // 0: the rig's default
};

// Builds the rig's model over a checked run file; throws RunFileError for bad
// input (missing metadata the replay needs, ...).
std::unique_ptr<RigModel> make_rig_model(RunFileRig rig, const RunFile& run, const RigModelOptions& options);

}  // namespace rigctl::diag
