// An operator command after it has been authenticated and decoded: what the
// rig state machine acts on. The wire format, its HMAC tag and the replay
// check live in tools/operator_auth.* (LCM type rigctl.operator_command_t);
// only commands that passed them reach the loop, through a lock-free queue.
#pragma once

#include <cstdint>
#include <string_view>

namespace rigctl {

enum class OperatorCommandKind : uint8_t {
  kHydraulicsOff,   // pressure off (only from a non-running state)
  kHydraulicsLow,   // stage 1: low pressure
  kHydraulicsHigh,  // stage 2: high pressure
  kArm,             // valve driven, holding the present position
  kStart,           // run the configured profile
  kHold,            // ramp the demand to a hold at the present position
  kResume,          // continue the profile after a hold
  kStop,            // controlled stop: ramp to hold, then disarm
  kReset,           // edge-triggered fault reset; succeeds only once every fault has cleared
  kSetpoint,        // change the held setpoint to `value` (SI), within the configured limits
  kStopAtBlockEnd,  // a test procedure runs on to the end of its present block, then a controlled stop
};

struct OperatorCommand {
  OperatorCommandKind kind = OperatorCommandKind::kStop;
  double value = 0.0;     // kSetpoint only
  uint64_t sequence = 0;  // sender's sequence number (already checked against replay)
};

constexpr std::string_view to_string(OperatorCommandKind k) {
  switch (k) {
    case OperatorCommandKind::kHydraulicsOff: return "hydraulics_off";
    case OperatorCommandKind::kHydraulicsLow: return "hydraulics_low";
    case OperatorCommandKind::kHydraulicsHigh: return "hydraulics_high";
    case OperatorCommandKind::kArm: return "arm";
    case OperatorCommandKind::kStart: return "start";
    case OperatorCommandKind::kHold: return "hold";
    case OperatorCommandKind::kResume: return "resume";
    case OperatorCommandKind::kStop: return "stop";
    case OperatorCommandKind::kReset: return "reset";
    case OperatorCommandKind::kSetpoint: return "setpoint";
    case OperatorCommandKind::kStopAtBlockEnd: return "stop_at_block_end";
  }
  return "unknown";
}

}  // namespace rigctl
