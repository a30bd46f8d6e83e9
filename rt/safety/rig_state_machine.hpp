// The rig's safety state machine: staged hydraulics, arming, running,
// holding, controlled stop and the latched fault, driven by operator commands
// and limit actions. Pure logic on the loop thread: no allocation, no I/O, no
// text (reasons are codes; text is made off the real-time path).
//
//   faulted --reset--> off --hyd_low--> hydraulics_low --hyd_high--> hydraulics_high --arm--> armed
//   armed --start--> running --hold--> holding --resume--> running
//   running|holding --stop--> stopping --(ramp settled)--> hydraulics_high
//   any --interlock--> faulted (valve safe at once, hydraulics off)
//
// The whole command table is kTransitions in rig_state_machine.cpp. Leaving
// running for any reason ramps the demand to a hold (DemandShaper): the
// demand's velocity is brought to zero at hold_deceleration, so position and
// velocity stay continuous; entering the profile again removes the offset
// between the held demand and the profile at setpoint_rate.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>

#include "rt/safety/limit_action.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/rig_state.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

inline constexpr std::size_t kOperatorCommandKindCount = 11;

// Why a command was refused. Codes on the loop; to_string off it.
enum class Rejection : uint8_t {
  kNone,
  kFaulted,             // faulted: only reset is accepted
  kFaultsActive,        // reset refused: a fault condition is still present
  kAlreadyInState,      // the command asks for the state the rig is in
  kHydraulicsOff,       // stage hydraulics to low first
  kNotLowPressure,      // high pressure only from low pressure
  kPressureNotReached,  // the present stage has not reached its pressure yet
  kNotHighPressure,     // arming needs high pressure
  kFeedbackInvalid,     // the valve is only driven on valid feedback
  kTripLatched,         // a latched limit trip (hold or worse) needs a reset first
  kValveDriven,         // hydraulics change refused while the valve is driven: stop first
  kNotArmed,            // start needs the rig armed
  kNotRunning,          // hold needs the rig running
  kNotHolding,          // resume needs the rig holding
  kUseResume,           // holding: resume continues the profile, start would restart it
  kNotDriven,           // stop/setpoint need the valve driven (armed, running or holding)
  kStopping,            // a controlled stop is in progress
  kSetpointOutOfRange,  // setpoint not finite or outside the configured range
  kNoProcedure,         // stop_at_block_end: no test procedure runs (the loop refuses it, not the table)
};
inline constexpr std::size_t kRejectionCount = 19;

std::string_view to_string(Rejection r);

// The rule for one (state, command) pair: a transition with a guard, or a
// refusal with its reason.
enum class Guard : uint8_t {
  kNone,
  kFaultsClear,       // reset: no fault condition present
  kLowPressure,       // hydraulics_low has reached its pressure
  kReadyToArm,        // high pressure reached, feedback valid, no latched trip
  kReadyToRun,        // feedback valid, no latched trip (start, resume)
  kSetpointInRange,   // setpoint finite and within [setpoint_min, setpoint_max]
};

struct TransitionRule {
  bool allowed = false;
  SafetyState to = SafetyState::kFaulted;  // allowed: the state after the command
  Guard guard = Guard::kNone;              // allowed: what must hold for it to succeed
  Rejection refused = Rejection::kNone;    // !allowed: why not
};

// kTransitions[state][command], the single table every command goes through.
const TransitionRule& transition_rule(SafetyState from, OperatorCommandKind command);

enum class DemandMode : uint8_t {
  kNone,     // valve not driven: the driver holds its safe command
  kHold,     // hold (or ramp to a hold) at DemandShaper's value
  kProfile,  // follow the profile (plus a decaying re-entry offset)
};

enum class HydraulicsStage : uint8_t { kOff, kLow, kHigh };

constexpr std::string_view to_string(HydraulicsStage s) {
  switch (s) {
    case HydraulicsStage::kOff: return "off";
    case HydraulicsStage::kLow: return "low";
    case HydraulicsStage::kHigh: return "high";
  }
  return "unknown";
}

struct StateMachineConfig {
  double period_s = 0.0025;
  // Timed staging (no pressure switch wired): a stage counts as reached this
  // long after it was commanded. 0: at once (the simulated supply is ideal).
  double low_settle_s = 0.0;
  double high_settle_s = 0.0;
  // [unit/s^2] how fast the demand's velocity is brought to zero when the
  // rig leaves running (hold, stop, hold/stop trips).
  double hold_deceleration = 1.0;
  // [unit/s] how fast a held demand moves to a new setpoint, and how fast the
  // offset between a held demand and the profile is removed on start/resume.
  double setpoint_rate = 0.05;
  double setpoint_min = -std::numeric_limits<double>::infinity();
  double setpoint_max = std::numeric_limits<double>::infinity();
  // A controlled stop that has not settled by then faults (valve safe at once).
  double stop_timeout_s = 5.0;
};

// Per-tick conditions, gathered by the loop before the machine steps.
struct MachineInputs {
  LimitAction limit_action = LimitAction::kNone;  // most severe active or latched trip
  bool faults_present = false;  // a detector condition is active now (reset would fail)
  bool feedback_valid = true;
  double feedback = 0.0;        // the controlled position, SI
  // A rig with several control channels: the controlled position of each
  // channel after the first (more_feedback[i - 1] is channel i's); arm holds
  // every channel where it stands.
  std::array<double, kMaxChannels - 1> more_feedback{};
  // Pressure switches where the rig has them; -1: not wired, use the settle time.
  int8_t low_pressure_reached = -1;
  int8_t high_pressure_reached = -1;
  bool reset_input = false;     // level of a hardware reset button: its rising edge resets
};

// The demand while the valve is driven: continuous position and velocity
// through every change of mode.
class DemandShaper {
 public:
  void configure(double period_s, double deceleration, double rate) noexcept;
  // Armed: hold exactly here, at rest.
  void hold_at(double position) noexcept;
  // Leave a moving demand: keep its velocity and decelerate it to rest.
  void ramp_to_hold() noexcept;
  // Move the held demand to `target` at the setpoint rate.
  void set_target(double target) noexcept {
    target_ = target;
    target_set_ = true;
  }
  // The next profile tick starts from the present demand: the offset is
  // removed at the setpoint rate.
  void enter_profile() noexcept { entering_profile_ = true; }

  double next_hold() noexcept;                     // one tick of hold / ramp
  double next_profile(double profile) noexcept;    // one tick of the profile plus the decaying offset
  bool settled() const noexcept { return velocity_ == 0.0 && demand_ == target_; }
  double demand() const noexcept { return demand_; }
  double velocity() const noexcept { return velocity_; }
  double target() const noexcept { return target_; }

 private:
  double period_s_ = 0.0025, deceleration_ = 1.0, rate_ = 0.05;
  double demand_ = 0.0, velocity_ = 0.0, target_ = 0.0, offset_ = 0.0;
  bool decelerating_ = false, entering_profile_ = false;
  bool target_set_ = false;  // a setpoint arrived while decelerating: keep it
};

// One state change, kept for the event log.
struct StateChange {
  SafetyState from = SafetyState::kFaulted;
  SafetyState to = SafetyState::kFaulted;
  EventCode cause = EventCode::kNone;  // kCommandAccepted, a limit code, kStopTimeout, ...
};

struct CommandResult {
  bool accepted = false;
  Rejection reason = Rejection::kNone;
  bool reset_latches = false;  // a reset succeeded: the loop clears the detectors' latches
};

class RigStateMachine {
 public:
  explicit RigStateMachine(const StateMachineConfig& config = {});

  // Back to power-on: faulted (the power-up latch), hydraulics off.
  void power_on() noexcept;

  // Start of a tick: take the conditions, advance timers and apply the
  // automatic transitions (limit actions, stop settled, reset button edge).
  // `trip_cause` names the limit code for the event log.
  void begin_tick(const MachineInputs& in, EventCode trip_cause = EventCode::kNone) noexcept;

  // An operator (or automatic-sequence) command, against the present state
  // and the inputs of begin_tick. Any number per tick.
  CommandResult apply(const OperatorCommand& command) noexcept;

  // Outputs for this tick.
  SafetyState state() const noexcept { return state_; }
  bool valve_enabled() const noexcept;
  DemandMode demand_mode() const noexcept;
  HydraulicsStage hydraulics() const noexcept;
  bool pressure_reached() const noexcept;  // the present stage's pressure
  // The profile's clock runs only while running (a hold freezes it).
  bool profile_clock_running() const noexcept { return state_ == SafetyState::kRunning; }

  // The demand for this tick: call once per tick while valve_enabled().
  // `profile` is used only in DemandMode::kProfile.
  double next_demand(double profile) noexcept;
  const DemandShaper& shaper() const noexcept { return shaper_; }

  // Several control channels (1 by default, at most kMaxChannels): every
  // channel's demand is shaped alike (arm holds it where it stands, a hold
  // or stop brakes it, start removes its offset to the profile); a setpoint
  // command moves only the first channel's. A stop settles when every
  // channel's demand is at rest. Set before power_on.
  void set_channel_count(std::size_t n) noexcept;
  std::size_t channel_count() const noexcept { return channel_count_; }
  // The demand of channel i >= 1 for this tick, like next_demand.
  double next_channel_demand(std::size_t channel, double profile) noexcept;

  // The profile ended while running (operator mode): ramp to a hold.
  void profile_finished() noexcept;

  // True when the last stop of the rig was caused by a limit trip (the run
  // then counts as faulted even though the valve went safe in a controlled way).
  bool stopped_by_trip() const noexcept { return stop_by_trip_; }

  // State changes since begin_tick (bounded; more are counted, not kept).
  const StateChange* changes() const noexcept { return changes_.data(); }
  std::size_t change_count() const noexcept { return change_count_ < changes_.size() ? change_count_ : changes_.size(); }

  const StateMachineConfig& config() const noexcept { return config_; }

 private:
  Rejection check_guard(Guard g, const OperatorCommand& c) const noexcept;
  void enter(SafetyState to, EventCode cause) noexcept;
  void settle_stop() noexcept;
  CommandResult reset() noexcept;

  StateMachineConfig config_;
  SafetyState state_ = SafetyState::kFaulted;
  MachineInputs in_;
  bool reset_input_was_ = true;  // a button held down at power-on is not an edge
  double stage_elapsed_s_ = 0.0;
  double stopping_elapsed_s_ = 0.0;
  bool stop_by_trip_ = false;
  DemandShaper shaper_;  // the first channel's
  std::array<DemandShaper, kMaxChannels - 1> more_shapers_{};  // channel i's at i - 1
  std::size_t channel_count_ = 1;
  // Every shaper of the rig's channels, the first one's first.
  template <class F>
  void each_shaper(F&& f) noexcept {
    f(shaper_, in_.feedback);
    for (std::size_t i = 1; i < channel_count_; ++i) f(more_shapers_[i - 1], in_.more_feedback[i - 1]);
  }
  bool all_settled() const noexcept;
  std::array<StateChange, 8> changes_{};
  std::size_t change_count_ = 0;
};

}  // namespace rigctl
