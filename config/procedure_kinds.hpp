// The names a procedure file (docs/procedures.md) may use for its step kinds
// and compensations (rt/procedure/procedure_spec.hpp, names included).
#pragma once

#include <array>
#include <string_view>

#include "config/kind_names.hpp"
#include "rt/procedure/procedure_spec.hpp"

namespace rigctl {

// kRepeatEnd is the reader's own marker: no file names it.
template <>
struct KindNames<StepKind> {
  static constexpr std::string_view noun = "step";
  static constexpr std::array known{StepKind::kRamp, StepKind::kHold, StepKind::kSine, StepKind::kBlocks,
                                    StepKind::kDrive, StepKind::kRepeatBegin};
};

template <>
struct KindNames<Compensation> {
  static constexpr std::string_view noun = "compensation";
  static constexpr std::array known{Compensation::kNone, Compensation::kAmplitudePhase, Compensation::kPeakValley};
};

}  // namespace rigctl
