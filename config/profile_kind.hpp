// `profile.type` of a config: the shape of the demand (rt/control/setpoint_profile.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "config/kind_names.hpp"

namespace rigctl {

enum class ProfileKind : uint8_t {
  kRampSteps,  // lead-in, then a staircase of steps
  kSine,       // lead-in, then a sine
  kCsv,        // a table from a CSV file, interpolated
  kHold,       // a constant demand (the half car: the body held at rest)
};

constexpr std::string_view to_string(ProfileKind k) {
  switch (k) {
    case ProfileKind::kRampSteps: return "ramp_steps";
    case ProfileKind::kSine: return "sine";
    case ProfileKind::kCsv: return "csv";
    case ProfileKind::kHold: return "hold";
  }
  return "unknown";
}

template <>
struct KindNames<ProfileKind> {
  static constexpr std::string_view noun = "profile";
  static constexpr std::array known{ProfileKind::kRampSteps, ProfileKind::kSine, ProfileKind::kCsv,
                                    ProfileKind::kHold};
};

}  // namespace rigctl
