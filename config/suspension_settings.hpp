// The half car's config sections beyond the plant, as settings: the
// active-suspension controllers (`controller:`), the passive-vs-active
// report (`report:`) and the design optimisation (`optimize:`). Read by
// config/suspension_controller_reader.hpp; apart from it so that a rig's
// config (config/rig_config.hpp, read nearly everywhere) does not bring the
// YAML reader's headers along.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "config/controller_kind.hpp"
#include "rt/control/fuzzy_engine.hpp"
#include "rt/control/fuzzy_suspension_controller.hpp"
#include "rt/control/lqr_controller.hpp"
#include "rt/control/suspension_controller.hpp"

namespace rigctl {

// The half car's controllers, in the order the report runs them.
inline std::vector<ControllerKind> suspension_controllers() { return controllers_of(RigKind::kHalfCar); }
// Their names, in that order: the report's table heads and JSON keys.
inline std::vector<std::string> suspension_controller_types() {
  std::vector<std::string> names;
  for (const ControllerKind k : suspension_controllers()) names.emplace_back(to_string(k));
  return names;
}

struct SuspensionControllerSettings {
  std::string output_1 = "f_1";  // actuator force outputs (driver output names)
  std::string output_2 = "f_2";
  double force_limit = kDefaultSuspensionForceLimit;  // [N] per actuator, every active controller
  FuzzyEngineSpec fuzzy = paper_fuzzy_spec();
  FuzzyFirstInput fuzzy_first_input = FuzzyFirstInput::kVelocity;
  double skyhook_c_sky = 4000.0;  // [N s/m]
  LqrWeights lqr;
};

// `report:` of `rigctl compare`.
struct SuspensionReportConfig {
  // Settling band: this fraction of the passive run's peak |z_s|, the same
  // band for every controller (so they are timed to one standard).
  double settling_band_fraction = 0.05;
  double settling_min_band = 0.0;  // [m] floor of the band
};

// A design variable of `rigctl optimize`: a HalfCarParams field and its
// bounds. Names: spring_1, spring_2 [N/m], damper_1, damper_2 [N s/m].
struct OptimizeVariable {
  std::string name;
  double min = 0.0, max = 0.0;
};

inline const std::vector<std::string>& optimize_variable_names() {
  static const std::vector<std::string> names{"spring_1", "damper_1", "spring_2", "damper_2"};
  return names;
}

// `optimize:` of `rigctl optimize`.
//   cost = w_comfort Wk/Wk0 + w_tyre T/T0 + w_travel S/S0
// with Wk the ISO 2631 Wk-weighted RMS body acceleration, T the RMS tyre
// deflection and S the RMS suspension travel (both corners), each divided by
// the initial design's value (so the cost of the initial design is the sum
// of the weights), subject to peak |suspension travel| <= travel_limit.
struct SuspensionOptimizeConfig {
  std::string algorithm = "crs2_lm";   // crs2_lm (constraint as a penalty) | isres (constraint native)
  ControllerKind controller = ControllerKind::kPassive;  // which controller runs during the search
  int evaluations = 300;               // simulation runs (the initial design not counted)
  uint64_t seed = 1;                   // NLopt's random seed: same seed, same search
  double duration_s = 10.0;            // [s] per evaluation
  double weight_comfort = 1.0;
  double weight_tyre = 0.5;
  double weight_travel = 0.25;
  double travel_limit = 0.08;          // [m] peak |suspension travel|
  double penalty = 10.0;               // crs2_lm: cost added per unit of relative constraint violation
  std::vector<OptimizeVariable> variables;
};

}  // namespace rigctl
