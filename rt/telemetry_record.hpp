// What the real-time loop hands to the publisher thread on every tick. Plain
// data of fixed size, so that pushing it into the lock-free queue is a copy.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "rt/procedure_status.hpp"
#include "rt/rig_state.hpp"
#include "rt/sample.hpp"
#include "rt/timing_summary.hpp"

namespace rigctl {

inline constexpr std::size_t kMaxControllerTerms = 8;

// The controller's inside view for one tick (what each field holds:
// rt/control/controller.hpp); term names come from
// Controller::term_names(), fixed at start-up.
struct ControllerTerms {
  double setpoint = 0.0;
  double measurement = 0.0;
  double error = 0.0;
  std::array<double, kMaxControllerTerms> term{};  // e.g. P part, I part
  double output_unsaturated = 0.0;
  double output = 0.0;
  bool saturated = false;
  bool integrator_held = false;  // anti-windup is holding the integrator this tick
};

// A control channel after the first, in brief: what the channels' message
// (lcmtypes/rigctl_channels_t.lcm) and the run file's x_ref_2... carry.
// Small, so the record a one-channel rig copies each tick stays small.
struct ChannelTerms {
  double setpoint = 0.0;
  double measurement = 0.0;
  double output = 0.0;  // the channel's first output as commanded
  bool saturated = false;
};

// Something that happened on this tick. Codes, not text: the publisher
// formats the message off the real-time path.
enum class EventCode : uint8_t {
  kNone,
  kRunStarted,
  kProfileFinished,
  kStopRequested,    // SIGINT/SIGTERM or --duration reached
  kLimitTripped,     // input `channel` left its range with `value`
  kInputInvalid,     // driver flagged input `channel` invalid (NaN, stale)
  kDriverReadFailed,  // no usable sample, or the driver could not deliver the commands
  kQueueOverflow,    // telemetry records were dropped (value = count)
  // Safety core (rt/safety/rig_state_machine.hpp, rt/safety/limit_detectors.hpp). `detail`
  // carries the command kind, rejection reason or limit action.
  kStateChanged,      // value = the previous SafetyState, detail = the new one
  kCommandAccepted,   // detail = OperatorCommandKind, value = its value
  kCommandRejected,   // detail = Rejection (rt/safety/rig_state_machine.hpp), channel = OperatorCommandKind
  kRateLimit,         // input `channel` changed faster than its limit (value = rate)
  kTrackingError,     // |demand - feedback| of input `channel` over its limit (value = error)
  kValveSaturated,    // output `channel` at its saturation level too long (value = command)
  kSampleStale,       // the sample time stamp stopped advancing (value = age [s])
  kOverruns,          // too many loop overruns in the window (value = count)
  kOpenCircuit,       // input `channel` at its rail: open-circuit transducer (value)
  kSensorStuck,       // input `channel` did not change while the valve was commanded (value)
  kStopTimeout,       // a controlled stop did not settle in time: valve made safe
  kLogWriteFailed,    // a log write failed (disk full, I/O error); the rig keeps running
  kFaultReset,        // every fault cleared and the latches were reset
  // Test procedures (rt/procedure/procedure_runner.hpp).
  kPeakValleyChange,   // input `channel`'s peaks/valleys left the step's reference (value = change, fraction of range)
  kCompensationLimit,  // the compensation needed more than its max_factor (value = factor): something broke
  kBlockEndStop,       // the block an operator asked to stop at has ended (value = test cycles done): a controlled stop
};

constexpr std::string_view to_string(EventCode c) {
  switch (c) {
    case EventCode::kNone: return "";
    case EventCode::kRunStarted: return "run_started";
    case EventCode::kProfileFinished: return "profile_finished";
    case EventCode::kStopRequested: return "stop_requested";
    case EventCode::kLimitTripped: return "limit_tripped";
    case EventCode::kInputInvalid: return "input_invalid";
    case EventCode::kDriverReadFailed: return "driver_read_failed";
    case EventCode::kQueueOverflow: return "queue_overflow";
    case EventCode::kStateChanged: return "state_changed";
    case EventCode::kCommandAccepted: return "command_accepted";
    case EventCode::kCommandRejected: return "command_rejected";
    case EventCode::kRateLimit: return "rate_limit";
    case EventCode::kTrackingError: return "tracking_error";
    case EventCode::kValveSaturated: return "valve_saturated";
    case EventCode::kSampleStale: return "sample_stale";
    case EventCode::kOverruns: return "overruns";
    case EventCode::kOpenCircuit: return "open_circuit";
    case EventCode::kSensorStuck: return "sensor_stuck";
    case EventCode::kStopTimeout: return "stop_timeout";
    case EventCode::kLogWriteFailed: return "log_write_failed";
    case EventCode::kFaultReset: return "fault_reset";
    case EventCode::kPeakValleyChange: return "peak_valley_change";
    case EventCode::kCompensationLimit: return "compensation_limit";
    case EventCode::kBlockEndStop: return "block_end_stop";
  }
  return "unknown";
}

struct Event {
  EventCode code = EventCode::kNone;
  int16_t channel = -1;  // input index the event is about, -1 when none
  double value = 0.0;
  uint8_t detail = 0;    // code-specific (see EventCode)
  uint8_t action = 0;    // LimitAction of a limit trip (rt/safety/limit_action.hpp), 0 otherwise
};

struct TelemetryRecord {
  int64_t tick = 0;
  // False on the record that closes a run: it carries only state, event and
  // timing, no sample/command/controller messages (the tick never ran).
  bool has_sample = true;
  Sample sample;
  Command command;
  ControllerTerms controller;  // the first control channel's
  // A rig with several control channels (a two-poster): how many, and
  // those after the first (more_channels[i - 1] is channel i).
  uint8_t channel_count = 1;
  std::array<ChannelTerms, kMaxChannels - 1> more_channels{};
  RigState state = RigState::kRunning;
  SafetyState safety_state = SafetyState::kRunning;
  bool valve_enabled = true;  // false: the driver holds its safe command, `command` was not written
  Event event;
  // A test procedure's step, counts and compensation (active: one runs).
  ProcedureStatus procedure;
  // Set on the ticks where the loop publishes its timing statistics.
  bool has_timing = false;
  TimingSummary timing;
};

}  // namespace rigctl
