// Rig states published with every sample: the coarse run state (what a run
// log reader needs: did it start, run, stop or fault) and the full safety
// state of rt/safety/rig_state_machine.hpp (what a test engineer sees on the HMI).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace rigctl {

enum class RigState : uint8_t {
  kStarting,  // driver started, first samples arriving
  kRunning,   // profile running under control
  kStopping,  // run over, outputs going to safe
  kStopped,   // outputs safe, loop ended normally
  kFaulted,   // a limit tripped or the driver failed: outputs safe
};

constexpr std::string_view to_string(RigState s) {
  switch (s) {
    case RigState::kStarting: return "starting";
    case RigState::kRunning: return "running";
    case RigState::kStopping: return "stopping";
    case RigState::kStopped: return "stopped";
    case RigState::kFaulted: return "faulted";
  }
  return "unknown";
}

// The safety state machine's states (rt/safety/rig_state_machine.hpp has the
// transition table). Order is fixed: tables and tests index by it.
enum class SafetyState : uint8_t {
  kOff,             // hydraulics off, valve at its safe command
  kHydraulicsLow,   // stage 1 pressure, valve safe
  kHydraulicsHigh,  // stage 2 (working) pressure, valve safe
  kArmed,           // valve driven, holding a position
  kRunning,         // valve driven, following the profile
  kHolding,         // valve driven, demand ramped to a hold
  kStopping,        // valve driven, demand ramping to a hold, then disarm
  kFaulted,         // interlock: valve safe at once, hydraulics off; reset needed
};
inline constexpr std::size_t kSafetyStateCount = 8;

constexpr std::string_view to_string(SafetyState s) {
  switch (s) {
    case SafetyState::kOff: return "off";
    case SafetyState::kHydraulicsLow: return "hydraulics_low";
    case SafetyState::kHydraulicsHigh: return "hydraulics_high";
    case SafetyState::kArmed: return "armed";
    case SafetyState::kRunning: return "running";
    case SafetyState::kHolding: return "holding";
    case SafetyState::kStopping: return "stopping";
    case SafetyState::kFaulted: return "faulted";
  }
  return "unknown";
}

}  // namespace rigctl
