// `rig:` of a config: which physical rig, hence which plant model, which
// controllers and which run-file columns. The names are those of the
// config files and run files (`# rig: quarter_car`).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "config/kind_names.hpp"

namespace rigctl {

enum class RigKind : uint8_t {
  kQuarterCar,       // hydraulic road simulator under a passive quarter car (seed paper 000)
  kPneumaticRotary,  // flexible-bladder rotary servo (seed paper 002)
  kHalfCar,          // half vehicle with active suspension (seed paper 001)
  kTwoPoster,        // seed 001's half car on two hydraulic posts like seed 000's (docs/rig-models.md 4)
};

constexpr std::string_view to_string(RigKind k) {
  switch (k) {
    case RigKind::kQuarterCar: return "quarter_car";
    case RigKind::kPneumaticRotary: return "pneumatic_rotary";
    case RigKind::kHalfCar: return "half_car";
    case RigKind::kTwoPoster: return "two_poster";
  }
  return "unknown";
}

template <>
struct KindNames<RigKind> {
  static constexpr std::string_view noun = "rig kind";
  static constexpr std::array known{RigKind::kQuarterCar, RigKind::kPneumaticRotary, RigKind::kHalfCar, RigKind::kTwoPoster};
};

}  // namespace rigctl
