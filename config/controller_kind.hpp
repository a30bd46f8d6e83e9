// `controller.type` of a config (and the half car's `optimize.controller`):
// which control law runs. Each rig runs the controllers of its paper, so a
// controller kind belongs to exactly one rig kind (rig_of).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "config/kind_names.hpp"
#include "config/rig_kind.hpp"

namespace rigctl {

class ConfigReader;

// The half car's four are in the order `rigctl compare` runs and reports
// them (passive first: the others are measured against it).
enum class ControllerKind : uint8_t {
  kPi,       // quarter_car: PI on the actuator position
  kPvp,      // pneumatic_rotary: P + velocity + differential pressure
  kPassive,  // half_car: no actuator force
  kFuzzy,    // half_car: the paper's fuzzy controller
  kSkyhook,  // half_car: skyhook damping (baseline)
  kLqr,      // half_car: LQR on the plant's states (baseline)
};

constexpr std::string_view to_string(ControllerKind k) {
  switch (k) {
    case ControllerKind::kPi: return "pi";
    case ControllerKind::kPvp: return "pvp";
    case ControllerKind::kPassive: return "passive";
    case ControllerKind::kFuzzy: return "fuzzy";
    case ControllerKind::kSkyhook: return "skyhook";
    case ControllerKind::kLqr: return "lqr";
  }
  return "unknown";
}

template <>
struct KindNames<ControllerKind> {
  static constexpr std::string_view noun = "controller";
  static constexpr std::array known{ControllerKind::kPi,      ControllerKind::kPvp,     ControllerKind::kPassive,
                                    ControllerKind::kFuzzy,   ControllerKind::kSkyhook, ControllerKind::kLqr};
};

// The rig kind a controller runs on.
constexpr RigKind rig_of(ControllerKind k) {
  switch (k) {
    case ControllerKind::kPi: return RigKind::kQuarterCar;
    case ControllerKind::kPvp: return RigKind::kPneumaticRotary;
    case ControllerKind::kPassive: return RigKind::kHalfCar;
    case ControllerKind::kFuzzy: return RigKind::kHalfCar;
    case ControllerKind::kSkyhook: return RigKind::kHalfCar;
    case ControllerKind::kLqr: return RigKind::kHalfCar;
  }
  return RigKind::kQuarterCar;
}

// The controllers of a rig kind, in enumerator order.
std::vector<ControllerKind> controllers_of(RigKind rig);
// Whether a rig kind may run a controller kind: its own (rig_of), and on the
// two-poster, whose posts are position loops, pi and pvp.
bool runs_on(ControllerKind k, RigKind rig);

// Reads a controller kind at `key` for a rig kind: an unknown name, or a
// controller of another rig, is a ConfigError naming file, line and key.
ControllerKind read_controller_kind(ConfigReader& r, const std::string& key, RigKind rig);

}  // namespace rigctl
