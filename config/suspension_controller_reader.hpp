// The half car's config sections beyond the plant: the active-suspension
// controllers (`controller:`), the passive-vs-active report (`report:`) and
// the design optimisation (`optimize:`). Strict like the rest of the config:
// every key required, errors name file, line and key.
//
// The fuzzy controller is read as a general Mamdani engine
// (rt/control/fuzzy_engine.hpp): two inputs and one output, each with its universe,
// scale and named membership functions, and the rule base as a table.
//
//   fuzzy:
//     first_input: velocity         # velocity | displacement (what input 1 measures)
//     resolution: 1001              # output samples for the centroid
//     inputs:                       # exactly two, in order (file order is kept)
//       velocity_error:
//         universe: [-1.0, 1.0]
//         scale: 10.0               # universe units per physical unit (here 1/(m/s))
//         sets:
//           NVL: {trapezoid: [-1.0, -1.0, -0.8, -0.6]}
//           NL: {triangle: [-0.8, -0.6, -0.4]}
//           ...
//       acceleration_error: {...}
//     output:
//       force: {universe: [-1, 1], scale: 2000.0, sets: {...}}   # N per universe unit
//     rules:                        # rows: input-1 sets; one output set per input-2 set,
//       NVL: "NVL NVL NL"           # in input 2's set order; "-" = no rule
//       ...
//
// A rule "NS: NM NS NS" with input 2's sets N, ZE, P reads: IF x1 is NS AND
// x2 is N THEN f is NM; IF x1 is NS AND x2 is ZE THEN f is NS; ...
#pragma once

#include "config/config_reader.hpp"
#include "config/suspension_settings.hpp"

namespace rigctl {

// Reads the half car's `controller:` keys after `type`, `feedback`: output_1,
// output_2, force_limit_n, fuzzy, skyhook, lqr (all required).
void read_suspension_controller(ConfigReader& r, SuspensionControllerSettings& s);

// Reads a fuzzy engine section (format above) into a spec; the engine is
// built once here so that its own checks (unknown set names, unordered
// points) fail at load with the key named.
FuzzyEngineSpec read_fuzzy_engine(ConfigReader r, FuzzyFirstInput& first_input);

SuspensionReportConfig read_suspension_report(ConfigReader r);

SuspensionOptimizeConfig read_suspension_optimize(ConfigReader r);

}  // namespace rigctl
