// What a limit detector does when it trips, in increasing severity. The rig
// state machine acts on the most severe action of all active or latched trips.
#pragma once

#include <cstdint>
#include <string_view>

namespace rigctl {

enum class LimitAction : uint8_t {
  kNone,       // nothing tripped
  kIndicate,   // report only: the run goes on
  kHold,       // ramp the demand to a hold (running -> holding)
  kStop,       // controlled stop: ramp to a hold, then disarm (valve safe, hydraulics stay)
  kInterlock,  // valve to its safe command at once, hydraulics off (faulted)
};

constexpr std::string_view to_string(LimitAction a) {
  switch (a) {
    case LimitAction::kNone: return "none";
    case LimitAction::kIndicate: return "indicate";
    case LimitAction::kHold: return "hold";
    case LimitAction::kStop: return "stop";
    case LimitAction::kInterlock: return "interlock";
  }
  return "unknown";
}

constexpr LimitAction more_severe(LimitAction a, LimitAction b) { return a < b ? b : a; }

}  // namespace rigctl
