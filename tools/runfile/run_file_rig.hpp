// The rig kinds of the run-file contract (docs/run-files.md 1.6): what a
// run file's `# rig:` and `rigctl diagnose --rig` name. The rigs rigctl
// controls (config/rig_kind.hpp) and two it only diagnoses: the EMPS linear
// axis and the MR damper, whose records come from elsewhere.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "config/kind_names.hpp"
#include "config/rig_kind.hpp"

namespace rigctl {

enum class RunFileRig : uint8_t {
  kQuarterCar,
  kPneumaticRotary,
  kHalfCar,
  kLinearAxis,  // the EMPS electromechanical positioning system (a real record)
  kDamper,      // the MR damper (a real record)
};

constexpr std::string_view to_string(RunFileRig k) {
  switch (k) {
    case RunFileRig::kQuarterCar: return "quarter_car";
    case RunFileRig::kPneumaticRotary: return "pneumatic_rotary";
    case RunFileRig::kHalfCar: return "half_car";
    case RunFileRig::kLinearAxis: return "linear_axis";
    case RunFileRig::kDamper: return "damper";
  }
  return "unknown";
}

template <>
struct KindNames<RunFileRig> {
  static constexpr std::string_view noun = "rig kind";
  static constexpr std::array known{RunFileRig::kQuarterCar, RunFileRig::kPneumaticRotary, RunFileRig::kHalfCar,
                                    RunFileRig::kLinearAxis, RunFileRig::kDamper};
};

// The run files a controlled rig writes (`rigctl run --csv`, make-run) when
// the diagnosis reads them; none for the two-poster (its run files are
// docs/run-files.md 1.7's, the diagnosis has no model of it yet).
constexpr std::optional<RunFileRig> run_file_rig(RigKind k) {
  switch (k) {
    case RigKind::kQuarterCar: return RunFileRig::kQuarterCar;
    case RigKind::kPneumaticRotary: return RunFileRig::kPneumaticRotary;
    case RigKind::kHalfCar: return RunFileRig::kHalfCar;
    case RigKind::kTwoPoster: return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace rigctl
