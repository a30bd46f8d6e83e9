// Hidden-effect generator for the diagnosis tests (`rigctl make-run`): a rig
// config is made "clean" (every effect of the diagnosis library at its null),
// chosen effects are switched on at a weak or strong level in one of their
// physical forms, then the world is made to differ from the model as a real
// rig does: every plant parameter drawn within a tolerance (+-5 % by
// default), the controller gains and the demand varied within the rig's
// stable range (perturbation.hpp). The real closed loop (RigLoop, simulated
// driver with sensor noise and quantisation) records a run file.
//
// Each effect has two physical forms, none of them the formula the diagnosis
// fits (Karnopp stick/slip and LuGre vs a smooth Stribeck curve, sharp and
// rounded spool lands vs a softplus dead zone, a cubic delay line and a
// conditioning filter vs a linearly interpolated delay, ...): the diagnosis
// must find the physics, not its own equations. docs/diagnosis.md 7 lists
// the forms and the ranges.
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
  std::string form;                     // the physical form made (e.g. "karnopp", "lugre")
};

class Perturbation;

// One rig kind's part of the generator (tools/hidden_effects/<rig>.cpp).
struct RigEffectGenerator {
  RigKind rig;
  std::vector<std::string> causes;  // every contract cause id of the rig except "none"
  std::string excitation_case;      // `cases:` entry of the rig's shipped config used for diagnosis runs
  // Switches off every plant effect the diagnosis library covers (the baseline
  // plant); make_run itself clears the sensor effects (offset, delay).
  void (*make_clean)(RigConfig& config);
  // Applies one effect at `level` in physical form `form` (0 or 1, see
  // kForms); throws std::invalid_argument for a cause id the rig does not have.
  AppliedEffect (*apply)(RigConfig& config, const std::string& cause, double level, int form);
  // Draws the plant parameters, controller gains and demand of one run
  // (after the effects are applied). `scratch` is a path prefix for a
  // varied demand table the run may need.
  void (*perturb)(RigConfig& config, Perturbation& draw, const std::string& scratch);
};

// Every effect of every rig has this many physical forms.
constexpr int kForms = 2;

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
  int seed = 1;             // sensor noise seed; also draws the perturbation and, unless `form` is set, the form
  double tolerance = 0.05;  // half-width of every plant parameter's draw; 0: the plant at nominal, no variation
  int form = -1;            // physical form of every effect (0, 1); -1: seed % 2
  std::string out_csv;      // run file
  std::string truth_json;   // optional: what was hidden, for tests and the benchmark sweep
};

// Runs the closed loop in fast mode and writes the run file; returns what was applied.
std::vector<AppliedEffect> make_run(const MakeRunOptions& options, std::ostream& progress);

}  // namespace rigctl
