// Hidden-effect generator for the diagnosis tests (`rigctl make-run`): a rig
// config is made "clean" (every effect of the diagnosis library at its null,
// so the plant is the diagnosis baseline), then chosen effects are switched
// on at a weak or strong level, and the real closed loop (RigLoop, simulated
// driver with sensor noise and quantisation) records a run file.
//
// The plant and sensor code that produces an effect is deliberately not the
// formula the diagnosis fits (Karnopp stick/slip vs a smooth Stribeck curve,
// a sharp dead zone vs a smooth one, a sensor delay interpolated cubically
// from a history vs linearly, ...): the diagnosis must find the physics, not
// its own equations.
#pragma once

#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "config/rig_config.hpp"

namespace rigctl {

// Strength of a hidden effect: 1 is "strong", weak_level() is "weak"; other
// positive values scale the strong effect's physical size linearly.
constexpr double weak_level() { return 0.35; }
// "weak" | "strong" | a positive number; throws std::invalid_argument naming the text.
double parse_effect_level(const std::string& text);

struct AppliedEffect {
  std::string cause;                    // contract cause id
  double level = 1.0;
  std::map<std::string, double> truth;  // physical parameters set, SI, named as the diagnosis reports them where they match
  std::string description;              // what was changed, for the truth file
};

// One rig kind's part of the generator (tools/hidden_effects/<rig>.cpp).
struct RigEffectGenerator {
  RigKind rig;
  std::vector<std::string> causes;  // every contract cause id of the rig except "none"
  std::string excitation_case;      // `cases:` entry of the rig's shipped config used for diagnosis runs
  // Switches off every plant effect the diagnosis library covers (the baseline
  // plant); make_run itself clears the sensor effects (offset, delay).
  void (*make_clean)(RigConfig& config);
  // Applies one effect at `level`; throws std::invalid_argument for a cause id the rig does not have.
  AppliedEffect (*apply)(RigConfig& config, const std::string& cause, double level);
};

// Registry: one generator per rig kind.
const RigEffectGenerator& effect_generator(RigKind rig);
// The same by the rig kind's name (callers holding a config file's name);
// throws std::invalid_argument naming the known rig kinds for another name.
const RigEffectGenerator& effect_generator(const std::string& rig);

struct MakeRunOptions {
  RigKind rig = RigKind::kQuarterCar;
  std::string config_path;  // default: config/<rig>.yaml beside the binary's source tree
  std::string case_name;    // default: the generator's excitation_case
  std::vector<std::pair<std::string, double>> effects;  // cause id, level
  double duration_s = 0.0;  // 0: the profile's length
  int seed = 1;             // sensor noise seed
  std::string out_csv;      // run file
  std::string truth_json;   // optional: what was hidden, for tests and the benchmark sweep
};

// Runs the closed loop in fast mode and writes the run file; returns what was applied.
std::vector<AppliedEffect> make_run(const MakeRunOptions& options, std::ostream& progress);

}  // namespace rigctl
