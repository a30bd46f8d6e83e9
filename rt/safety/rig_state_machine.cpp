#include "rt/safety/rig_state_machine.hpp"

namespace rigctl {

namespace {

using S = SafetyState;
using R = Rejection;

constexpr TransitionRule go(S to, Guard guard = Guard::kNone) { return {true, to, guard, R::kNone}; }
constexpr TransitionRule no(R why) { return {false, S::kFaulted, Guard::kNone, why}; }

// Every command in every state, in one place. Columns follow
// OperatorCommandKind: hyd_off, hyd_low, hyd_high, arm, start, hold, resume,
// stop, reset, setpoint, stop_at_block_end (a request to a running or held
// test procedure: the state stays; the procedure's block end stops the rig). A reset outside `faulted` keeps the state and
// clears the latches of trips whose condition has gone.
constexpr TransitionRule kTransitions[kSafetyStateCount][kOperatorCommandKindCount] = {
    // off
    {no(R::kAlreadyInState), go(S::kHydraulicsLow), no(R::kHydraulicsOff), no(R::kNotHighPressure),
     no(R::kNotArmed), no(R::kNotRunning), no(R::kNotHolding), no(R::kNotDriven), go(S::kOff, Guard::kFaultsClear),
     no(R::kNotDriven), no(R::kNotRunning)},
    // hydraulics_low
    {go(S::kOff), no(R::kAlreadyInState), go(S::kHydraulicsHigh, Guard::kLowPressure), no(R::kNotHighPressure),
     no(R::kNotArmed), no(R::kNotRunning), no(R::kNotHolding), no(R::kNotDriven),
     go(S::kHydraulicsLow, Guard::kFaultsClear), no(R::kNotDriven), no(R::kNotRunning)},
    // hydraulics_high
    {go(S::kOff), go(S::kHydraulicsLow), no(R::kAlreadyInState), go(S::kArmed, Guard::kReadyToArm), no(R::kNotArmed),
     no(R::kNotRunning), no(R::kNotHolding), no(R::kNotDriven), go(S::kHydraulicsHigh, Guard::kFaultsClear),
     no(R::kNotDriven), no(R::kNotRunning)},
    // armed: stop disarms at once (the demand is already a hold at rest)
    {no(R::kValveDriven), no(R::kValveDriven), no(R::kAlreadyInState), no(R::kAlreadyInState),
     go(S::kRunning, Guard::kReadyToRun), no(R::kNotRunning), no(R::kNotHolding), go(S::kHydraulicsHigh),
     go(S::kArmed, Guard::kFaultsClear), go(S::kArmed, Guard::kSetpointInRange), no(R::kNotRunning)},
    // running
    {no(R::kValveDriven), no(R::kValveDriven), no(R::kAlreadyInState), no(R::kAlreadyInState),
     no(R::kAlreadyInState), go(S::kHolding), no(R::kNotHolding), go(S::kStopping),
     go(S::kRunning, Guard::kFaultsClear), no(R::kNotHolding), go(S::kRunning)},
    // holding
    {no(R::kValveDriven), no(R::kValveDriven), no(R::kAlreadyInState), no(R::kAlreadyInState), no(R::kUseResume),
     no(R::kAlreadyInState), go(S::kRunning, Guard::kReadyToRun), go(S::kStopping),
     go(S::kHolding, Guard::kFaultsClear), go(S::kHolding, Guard::kSetpointInRange), go(S::kHolding)},
    // stopping: nothing interrupts a controlled stop but a fault
    {no(R::kStopping), no(R::kStopping), no(R::kStopping), no(R::kStopping), no(R::kStopping), no(R::kStopping),
     no(R::kStopping), no(R::kStopping), no(R::kStopping), no(R::kStopping), no(R::kStopping)},
    // faulted: only a reset, and only with every fault gone
    {no(R::kFaulted), no(R::kFaulted), no(R::kFaulted), no(R::kFaulted), no(R::kFaulted), no(R::kFaulted),
     no(R::kFaulted), no(R::kFaulted), go(S::kOff, Guard::kFaultsClear), no(R::kFaulted), no(R::kFaulted)},
};

constexpr bool valve_driven(S s) {
  return s == S::kArmed || s == S::kRunning || s == S::kHolding || s == S::kStopping;
}

double sign(double v) { return v < 0.0 ? -1.0 : 1.0; }

}  // namespace

std::string_view to_string(Rejection r) {
  switch (r) {
    case R::kNone: return "";
    case R::kFaulted: return "the rig is faulted: reset first";
    case R::kFaultsActive: return "a fault is still present: clear it, then reset";
    case R::kAlreadyInState: return "already in that state";
    case R::kHydraulicsOff: return "hydraulics are off: stage low pressure first";
    case R::kNotLowPressure: return "high pressure only from low pressure";
    case R::kPressureNotReached: return "the hydraulics have not reached the stage's pressure yet";
    case R::kNotHighPressure: return "arming needs high pressure";
    case R::kFeedbackInvalid: return "feedback is not valid: the valve is not driven";
    case R::kTripLatched: return "a limit trip is latched: reset first";
    case R::kValveDriven: return "the valve is driven: stop first";
    case R::kNotArmed: return "the rig is not armed";
    case R::kNotRunning: return "the rig is not running";
    case R::kNotHolding: return "the rig is not holding";
    case R::kUseResume: return "holding: resume continues the profile";
    case R::kNotDriven: return "the valve is not driven (arm first)";
    case R::kStopping: return "a controlled stop is in progress";
    case R::kSetpointOutOfRange: return "setpoint outside the configured range";
    case R::kNoProcedure: return "no test procedure runs";
  }
  return "unknown";
}

const TransitionRule& transition_rule(SafetyState from, OperatorCommandKind command) {
  return kTransitions[static_cast<std::size_t>(from)][static_cast<std::size_t>(command)];
}

// ---- DemandShaper ----

void DemandShaper::configure(double period_s, double deceleration, double rate) noexcept {
  period_s_ = period_s;
  deceleration_ = deceleration;
  rate_ = rate;
}

void DemandShaper::hold_at(double position) noexcept {
  demand_ = target_ = position;
  velocity_ = offset_ = 0.0;
  decelerating_ = entering_profile_ = false;
}

void DemandShaper::ramp_to_hold() noexcept {
  entering_profile_ = false;
  target_set_ = false;
  // A demand slower than one tick's deceleration stops at once: that is
  // within the deceleration limit, and a profile that has ended stops here.
  if (std::abs(velocity_) <= deceleration_ * period_s_) {
    velocity_ = 0.0;
    decelerating_ = false;
    target_ = demand_;
  } else {
    decelerating_ = true;
  }
}

double DemandShaper::next_hold() noexcept {
  if (decelerating_) {
    const double step = deceleration_ * period_s_;
    if (std::abs(velocity_) <= step) {
      velocity_ = 0.0;
      decelerating_ = false;
      if (!target_set_) target_ = demand_;
    } else {
      velocity_ -= sign(velocity_) * step;
      demand_ += velocity_ * period_s_;
    }
    return demand_;
  }
  const double diff = target_ - demand_;
  const double max_step = rate_ * period_s_;
  const double step = std::abs(diff) <= max_step ? diff : sign(diff) * max_step;
  demand_ = std::abs(diff) <= max_step ? target_ : demand_ + step;
  velocity_ = step / period_s_;
  return demand_;
}

double DemandShaper::next_profile(double profile) noexcept {
  if (entering_profile_) {
    offset_ = demand_ - profile;
    entering_profile_ = false;
    decelerating_ = false;
  }
  const double max_step = rate_ * period_s_;
  offset_ = std::abs(offset_) <= max_step ? 0.0 : offset_ - sign(offset_) * max_step;
  const double next = profile + offset_;
  velocity_ = (next - demand_) / period_s_;
  demand_ = target_ = next;
  return demand_;
}

// ---- RigStateMachine ----

RigStateMachine::RigStateMachine(const StateMachineConfig& config) : config_(config) {
  shaper_.configure(config.period_s, config.hold_deceleration, config.setpoint_rate);
  for (auto& m : more_shapers_) m.configure(config.period_s, config.hold_deceleration, config.setpoint_rate);
  power_on();
}

void RigStateMachine::set_channel_count(std::size_t n) noexcept {
  channel_count_ = n < 1 ? 1 : n > kMaxChannels ? kMaxChannels : n;
}

bool RigStateMachine::all_settled() const noexcept {
  if (!shaper_.settled()) return false;
  for (std::size_t i = 1; i < channel_count_; ++i)
    if (!more_shapers_[i - 1].settled()) return false;
  return true;
}

double RigStateMachine::next_channel_demand(std::size_t channel, double profile) noexcept {
  if (channel == 0) return next_demand(profile);
  DemandShaper& s = more_shapers_[channel - 1];
  return demand_mode() == DemandMode::kProfile ? s.next_profile(profile) : s.next_hold();
}

void RigStateMachine::power_on() noexcept {
  state_ = S::kFaulted;  // the power-up latch: a reset is the first thing an operator does
  in_ = MachineInputs{};
  reset_input_was_ = true;
  stage_elapsed_s_ = stopping_elapsed_s_ = 0.0;
  stop_by_trip_ = false;
  change_count_ = 0;
}

bool RigStateMachine::valve_enabled() const noexcept { return valve_driven(state_); }

DemandMode RigStateMachine::demand_mode() const noexcept {
  if (state_ == S::kRunning) return DemandMode::kProfile;
  return valve_driven(state_) ? DemandMode::kHold : DemandMode::kNone;
}

HydraulicsStage RigStateMachine::hydraulics() const noexcept {
  switch (state_) {
    case S::kOff:
    case S::kFaulted: return HydraulicsStage::kOff;
    case S::kHydraulicsLow: return HydraulicsStage::kLow;
    default: return HydraulicsStage::kHigh;
  }
}

bool RigStateMachine::pressure_reached() const noexcept {
  if (state_ == S::kHydraulicsLow) {
    if (in_.low_pressure_reached >= 0) return in_.low_pressure_reached > 0;
    return stage_elapsed_s_ >= config_.low_settle_s;
  }
  if (hydraulics() == HydraulicsStage::kHigh) {
    if (in_.high_pressure_reached >= 0) return in_.high_pressure_reached > 0;
    return stage_elapsed_s_ >= config_.high_settle_s;
  }
  return false;
}

void RigStateMachine::enter(SafetyState to, EventCode cause) noexcept {
  const S from = state_;
  if (to == S::kHydraulicsLow || (to == S::kHydraulicsHigh && from == S::kHydraulicsLow)) stage_elapsed_s_ = 0.0;
  if (to == S::kStopping) stopping_elapsed_s_ = 0.0;
  state_ = to;
  if (change_count_ < changes_.size()) changes_[change_count_] = StateChange{from, to, cause};
  ++change_count_;
}

void RigStateMachine::settle_stop() noexcept {
  if (state_ == S::kStopping && all_settled()) enter(S::kHydraulicsHigh, EventCode::kNone);
}

void RigStateMachine::begin_tick(const MachineInputs& in, EventCode trip_cause) noexcept {
  in_ = in;
  change_count_ = 0;
  stage_elapsed_s_ += config_.period_s;

  if (state_ != S::kFaulted) {
    if (in.limit_action == LimitAction::kInterlock) {
      enter(S::kFaulted, trip_cause);
    } else if (valve_driven(state_) && !in.feedback_valid) {
      enter(S::kFaulted, EventCode::kInputInvalid);
    } else if (in.limit_action == LimitAction::kStop &&
               (state_ == S::kArmed || state_ == S::kRunning || state_ == S::kHolding)) {
      stop_by_trip_ = true;
      each_shaper([](DemandShaper& d, double) { d.ramp_to_hold(); });
      enter(S::kStopping, trip_cause);
      settle_stop();
    } else if (in.limit_action == LimitAction::kHold && state_ == S::kRunning) {
      each_shaper([](DemandShaper& d, double) { d.ramp_to_hold(); });
      enter(S::kHolding, trip_cause);
    }
  }
  if (state_ == S::kStopping) {
    stopping_elapsed_s_ += config_.period_s;
    settle_stop();
    if (state_ == S::kStopping && stopping_elapsed_s_ > config_.stop_timeout_s) enter(S::kFaulted, EventCode::kStopTimeout);
  }
  // The reset button acts on its rising edge only: holding it down while a
  // fault clears does not reset the rig behind the operator's back.
  const bool edge = in.reset_input && !reset_input_was_;
  reset_input_was_ = in.reset_input;
  if (edge) apply(OperatorCommand{OperatorCommandKind::kReset, 0.0, 0});
}

Rejection RigStateMachine::check_guard(Guard g, const OperatorCommand& c) const noexcept {
  const bool latched = in_.limit_action >= LimitAction::kHold;
  switch (g) {
    case Guard::kNone: return R::kNone;
    case Guard::kFaultsClear: return in_.faults_present ? R::kFaultsActive : R::kNone;
    case Guard::kLowPressure: return pressure_reached() ? R::kNone : R::kPressureNotReached;
    case Guard::kReadyToArm:
      if (!pressure_reached()) return R::kPressureNotReached;
      if (!in_.feedback_valid) return R::kFeedbackInvalid;
      return latched ? R::kTripLatched : R::kNone;
    case Guard::kReadyToRun:
      if (!in_.feedback_valid) return R::kFeedbackInvalid;
      return latched ? R::kTripLatched : R::kNone;
    case Guard::kSetpointInRange:
      return std::isfinite(c.value) && c.value >= config_.setpoint_min && c.value <= config_.setpoint_max
                 ? R::kNone
                 : R::kSetpointOutOfRange;
  }
  return R::kNone;
}

CommandResult RigStateMachine::apply(const OperatorCommand& command) noexcept {
  CommandResult result;
  const auto kind_index = static_cast<std::size_t>(command.kind);
  if (kind_index >= kOperatorCommandKindCount) {
    result.reason = R::kNotDriven;
    return result;
  }
  const TransitionRule& rule = transition_rule(state_, command.kind);
  if (!rule.allowed) {
    result.reason = rule.refused;
    return result;
  }
  result.reason = check_guard(rule.guard, command);
  if (result.reason != R::kNone) return result;
  result.accepted = true;

  const S from = state_;
  switch (command.kind) {
    case OperatorCommandKind::kReset:
      result.reset_latches = true;
      stop_by_trip_ = false;
      break;
    case OperatorCommandKind::kArm: each_shaper([](DemandShaper& d, double at) { d.hold_at(at); }); break;
    case OperatorCommandKind::kStart:
    case OperatorCommandKind::kResume: each_shaper([](DemandShaper& d, double) { d.enter_profile(); }); break;
    case OperatorCommandKind::kHold: each_shaper([](DemandShaper& d, double) { d.ramp_to_hold(); }); break;
    case OperatorCommandKind::kStop:
      stop_by_trip_ = false;
      if (from != S::kArmed) each_shaper([](DemandShaper& d, double) { d.ramp_to_hold(); });
      break;
    case OperatorCommandKind::kSetpoint: shaper_.set_target(command.value); break;
    default: break;
  }
  if (rule.to != from) enter(rule.to, EventCode::kCommandAccepted);
  settle_stop();  // a stop of a demand already at rest completes at once
  return result;
}

double RigStateMachine::next_demand(double profile) noexcept {
  return demand_mode() == DemandMode::kProfile ? shaper_.next_profile(profile) : shaper_.next_hold();
}

void RigStateMachine::profile_finished() noexcept {
  if (state_ != S::kRunning) return;
  each_shaper([](DemandShaper& d, double) { d.ramp_to_hold(); });
  enter(S::kHolding, EventCode::kProfileFinished);
}

}  // namespace rigctl
