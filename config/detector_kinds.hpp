// `safety.detectors.NAME.type` of a config: the limit detectors' kinds are
// rt's own (rt/safety/detector_kind.hpp, names included); a config may name
// every one but `invalid`, the plausibility check that rig assembly gives
// every input by itself.
#pragma once

#include <array>
#include <string_view>

#include "config/kind_names.hpp"
#include "rt/safety/detector_kind.hpp"

namespace rigctl {

template <>
struct KindNames<DetectorKind> {
  static constexpr std::string_view noun = "detector";
  static constexpr std::array known{DetectorKind::kRange,      DetectorKind::kRate,
                                    DetectorKind::kTrackingError, DetectorKind::kValveSaturation,
                                    DetectorKind::kSampleAge,  DetectorKind::kOverruns,
                                    DetectorKind::kOpenCircuit, DetectorKind::kStuck};
};

}  // namespace rigctl
