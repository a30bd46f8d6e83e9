// Coarse rig states published with every sample. The full state machine with
// staged hydraulics and interlocks builds on these.
#pragma once

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

}  // namespace rigctl
