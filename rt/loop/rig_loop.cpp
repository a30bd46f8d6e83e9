#include "rt/loop/rig_loop.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rigctl {

namespace {

StateMachineConfig with_period(StateMachineConfig c, int64_t period_ns) {
  c.period_s = static_cast<double>(period_ns) * 1e-9;
  return c;
}

// The record's coarse state: before the rig first ran it is "starting".
RigState coarse_state(SafetyState s, bool ever_ran) noexcept {
  switch (s) {
    case SafetyState::kRunning:
    case SafetyState::kHolding: return RigState::kRunning;
    case SafetyState::kStopping: return RigState::kStopping;
    case SafetyState::kFaulted: return ever_ran ? RigState::kFaulted : RigState::kStarting;
    default: return ever_ran ? RigState::kStopped : RigState::kStarting;
  }
}

constexpr OperatorCommand kStopCommand{OperatorCommandKind::kStop, 0.0, 0};
constexpr OperatorCommand kHydraulicsOffCommand{OperatorCommandKind::kHydraulicsOff, 0.0, 0};

}  // namespace

RigLoop::RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, LimitDetectors detectors,
                 TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options, const SafetyOptions& safety)
    : driver_(driver), controller_(controller), profile_(profile), detectors_(std::move(detectors)),
      telemetry_(telemetry), clock_(clock), options_(options), safety_(safety),
      machine_(with_period(safety.machine, options.period_ns)), timing_(options.period_ns, options.overrun_policy) {}

void RigLoop::set_more_channels(std::span<const ControlChannel> channels) {
  if (channels.size() > more_channels_.size()) {
    throw std::invalid_argument("rig loop: " + std::to_string(channels.size() + 1) + " control channels, at most " +
                                std::to_string(kMaxChannels));
  }
  for (const ControlChannel& c : channels) {
    if (c.controller == nullptr || c.profile == nullptr || c.feedback_input < 0 ||
        c.feedback_input >= static_cast<int>(kMaxInputs)) {
      throw std::invalid_argument("rig loop: a control channel without a controller, profile or feedback input");
    }
  }
  std::copy(channels.begin(), channels.end(), more_channels_.begin());
  more_count_ = channels.size();
  machine_.set_channel_count(1 + more_count_);
}

void RigLoop::set_procedure(ProcedureRunner* procedure, RecoverySink* recovery, int64_t recovery_every_ticks) {
  procedure_ = procedure;
  recovery_sink_ = recovery;
  recovery_every_ticks_ = recovery_every_ticks;
  if (recovery_sink_ != nullptr) recovery_ = std::make_unique<ProcedureRecovery>();
}

LoopResult RigLoop::run(const std::atomic<bool>& stop_requested) {
  RunState run;
  begin_run(run);
  try {
    for (;; ++run.tick) {
      wait(run);
      if (notice_stop_request(stop_requested, run) == Step::kEndRun) break;
      if (read(run) == Step::kEndRun) break;
      stamp(TickStage::kRead);
      if (check(run) == Step::kEndRun) break;
      stamp(TickStage::kCheck);
      take_commands(run);
      stamp(TickStage::kCommands);
      demand(run);
      stamp(TickStage::kDemand);
      control_and_write(run);  // stamps kControl and kWrite
      hand_off(run);           // stamps kHandOff
      if (decide_end(run) == Step::kEndRun) {
        ++run.tick;  // this tick was handed off: it counts
        break;
      }
    }
  } catch (...) {
    // Drivers may throw on a broken device; the outputs go safe before the
    // exception leaves the loop.
    driver_.make_safe();
    throw;
  }
  driver_.make_safe();
  return finish_run(run);
}

void RigLoop::begin_run(RunState& run) noexcept {
  controller_.reset();
  profile_.reset();
  for (std::size_t i = 0; i < more_count_; ++i) {
    more_channels_[i].controller->reset();
    more_channels_[i].profile->reset();
  }
  machine_.power_on();
  commands_.restart(safety_.auto_sequence);
  run.feedback_input = safety_.feedback_input >= 0
                           ? safety_.feedback_input
                           : (options_.start_from_input >= 0 ? options_.start_from_input : 0);
  run.deadline_ns = clock_.now_ns();
}

// ---- wait

void RigLoop::wait(RunState& run) noexcept {
  clock_.sleep_until(run.deadline_ns);
  run.woke_ns = clock_.now_ns();
  timing_.on_wake(run.deadline_ns, run.woke_ns);
}

RigLoop::Step RigLoop::notice_stop_request(const std::atomic<bool>& stop_requested, RunState& run) noexcept {
  if (!stop_requested.load(std::memory_order_relaxed) || run.stop_request_seen) return Step::kCarryOn;
  run.stop_request_seen = true;
  run.end_event = Event{EventCode::kStopRequested, -1, 0.0};
  commands_.request_stop();  // its stop goes in on this tick's commands step
  return machine_.valve_enabled() ? Step::kCarryOn : Step::kEndRun;  // nothing to ramp: the rig is already safe
}

// ---- read

RigLoop::Step RigLoop::read(RunState& run) {
  run.record = TelemetryRecord{};
  run.record.tick = run.tick;
  run.command_event = Event{};
  run.procedure_trip = Event{};
  if (!driver_.read(run.record.sample)) {
    run.end_event = Event{EventCode::kDriverReadFailed, -1, 0.0};
    run.ended_by_fault = true;
    return Step::kEndRun;
  }
  if (run.tick == 0) {
    run.profile_clock.first_t_ns = run.previous_t_ns = run.t_ns();
    events_.log(loop_event(0, run.t_ns(), machine_.state(), Event{EventCode::kRunStarted, -1, 0.0}));
  }
  return Step::kCarryOn;
}

// ---- check: limit detectors, then the state machine

RigLoop::Step RigLoop::check(RunState& run) noexcept {
  const DetectorResult& trips = judge_limits(run);
  return step_state_machine(trips, run);
}

// The detectors judge this tick's sample against what the previous tick
// commanded (that is what acted on the rig until now).
const DetectorResult& RigLoop::judge_limits(RunState& run) noexcept {
  DetectorInputs in;
  in.sample = &run.record.sample;
  in.now_ns = run.woke_ns;
  in.demand = run.previous_demand;
  in.command = &run.previous_command;
  in.valve_driven = machine_.valve_enabled();
  in.overruns = timing_.overruns();
  const DetectorResult& trips = detectors_.check(in);
  const std::size_t kept = trips.new_count < kMaxTripsPerTick ? trips.new_count : kMaxTripsPerTick;
  for (std::size_t i = 0; i < kept; ++i) {
    const Event trip = trips.new_trips[i].event();
    if (trip.action > run.worst_trip.action) run.worst_trip = trip;
    events_.log(loop_event(run.tick, run.t_ns(), machine_.state(), trip));
  }
  return trips;
}

RigLoop::Step RigLoop::step_state_machine(const DetectorResult& trips, RunState& run) noexcept {
  MachineInputs in;
  // The procedure's own trips (peak-valley change, compensation limit) act
  // like a detector's, latched until a reset.
  in.limit_action = procedure_ != nullptr ? more_severe(trips.action, procedure_->action()) : trips.action;
  in.faults_present = trips.faults_present;
  in.feedback_valid = !trips.feedback_invalid;
  in.feedback = run.record.sample.value[static_cast<std::size_t>(run.feedback_input)];
  for (std::size_t i = 0; i < more_count_; ++i)
    in.more_feedback[i] = run.record.sample.value[static_cast<std::size_t>(more_channels_[i].feedback_input)];
  run.feedback = in.feedback;
  events_.begin_tick();
  const SafetyState before = machine_.state();
  machine_.begin_tick(in, run.worst_trip.code);
  const bool faulted_now = machine_.state() == SafetyState::kFaulted && before != SafetyState::kFaulted;
  if (faulted_now) {
    driver_.make_safe();  // a fault puts the valve to its safe command at once
    run.valve_was_enabled = false;
  }
  if (!safety_.auto_sequence) return Step::kCarryOn;
  // Without an operator an interlock or a fault ends the run on this tick,
  // before anything is written (what `rigctl run` has always done).
  if (trips.action == LimitAction::kInterlock) {
    events_.log_state_changes(machine_, run.tick, run.t_ns());
    run.end_event = run.worst_trip.code != EventCode::kNone ? run.worst_trip : trips.worst_new.event();
    run.ended_by_fault = true;
    return Step::kEndRun;
  }
  if (faulted_now) {
    events_.log_state_changes(machine_, run.tick, run.t_ns());
    const StateChange& last = machine_.changes()[machine_.change_count() - 1];
    run.end_event = Event{last.cause, -1, 0.0};
    run.ended_by_fault = true;
    return Step::kEndRun;
  }
  return Step::kCarryOn;
}

// ---- commands

void RigLoop::take_commands(RunState& run) noexcept {
  commands_.take([&](const OperatorCommand& c, const CommandSource& source) {
    return apply_command(c, source.origin(), source.logs_refusals(), run).accepted;
  });
  events_.log_state_changes(machine_, run.tick, run.t_ns());
}

// One command through the state machine, with its consequences for the
// detectors, the controller and the profile, and its event.
CommandResult RigLoop::apply_command(const OperatorCommand& c, EventSource source, bool log_refusal,
                                     RunState& run) noexcept {
  // A request to the test procedure: without one there is no block to end.
  const bool no_procedure = c.kind == OperatorCommandKind::kStopAtBlockEnd && procedure_ == nullptr;
  const CommandResult r = no_procedure ? CommandResult{false, Rejection::kNoProcedure, false} : machine_.apply(c);
  if (r.accepted) on_accepted(c, source, r, run);
  if (r.accepted || log_refusal) log_command(c, source, r, run);
  events_.log_state_changes(machine_, run.tick, run.t_ns());  // the state change right after its command
  return r;
}

void RigLoop::on_accepted(const OperatorCommand& c, EventSource source, const CommandResult& r, RunState& run) noexcept {
  if (r.reset_latches) {
    detectors_.clear_latches();
    if (procedure_ != nullptr) procedure_->clear_latch();
    run.worst_trip = Event{};
  }
  switch (c.kind) {
    case OperatorCommandKind::kArm:  // take over the valves with fresh integrators
      controller_.reset();
      for (std::size_t i = 0; i < more_count_; ++i) more_channels_[i].controller->reset();
      break;
    case OperatorCommandKind::kStop:
      if (source == EventSource::kOperator) run.operator_stopped = true;
      break;
    case OperatorCommandKind::kResume:
      // A procedure continues its step from where the hold left the demand.
      if (procedure_ != nullptr) procedure_->start(run.previous_demand);
      break;
    case OperatorCommandKind::kStopAtBlockEnd: procedure_->request_stop_at_block_end(); break;
    case OperatorCommandKind::kStart:
      run.operator_stopped = false;  // a new test after a re-arm
      if (procedure_ != nullptr) {
        // A procedure is not restarted: it continues (or begins) from here.
        procedure_->start(run.previous_demand);
        break;
      }
      // The profile from its beginning: its clock restarts at this sample.
      profile_.reset();
      run.profile_clock.restart_at(run.t_ns());
      if (options_.start_from_input >= 0) {
        profile_.start_from(run.record.sample.value[static_cast<std::size_t>(options_.start_from_input)]);
      }
      for (std::size_t i = 0; i < more_count_; ++i) {
        FilteredProfile& p = *more_channels_[i].profile;
        p.reset();
        // A bumpless start is the rig's choice: every channel from where it stands.
        if (options_.start_from_input >= 0) {
          p.start_from(run.record.sample.value[static_cast<std::size_t>(more_channels_[i].feedback_input)]);
        }
      }
      break;
    default: break;
  }
}

void RigLoop::log_command(const OperatorCommand& c, EventSource source, const CommandResult& r, RunState& run) noexcept {
  EventRecord e = loop_event(run.tick, run.t_ns(), machine_.state(),
                             r.accepted ? Event{EventCode::kCommandAccepted, -1, c.value, static_cast<uint8_t>(c.kind), 0}
                                        : Event{EventCode::kCommandRejected, static_cast<int16_t>(c.kind), c.value,
                                                static_cast<uint8_t>(r.reason), 0});
  e.source = source;
  e.sequence = c.sequence;
  events_.log(e);
  // The record shows what an operator or a signal asked for; the automatic
  // sequence's commands are only in the event log.
  if (source == EventSource::kOperator || source == EventSource::kSignal) run.command_event = e.event;
}

// ---- demand

void RigLoop::demand(RunState& run) noexcept {
  run.valve_enabled = machine_.valve_enabled();
  if (!run.valve_enabled && run.valve_was_enabled) driver_.make_safe();  // disarmed on this tick
  if (run.tick > 0 && !machine_.profile_clock_running()) run.profile_clock.freeze_for(run.t_ns() - run.previous_t_ns);
  run.demand = run.previous_demand;
  if (!run.valve_enabled) return;
  const bool profile_mode = machine_.demand_mode() == DemandMode::kProfile;
  const double profile = !profile_mode ? 0.0 : procedure_ != nullptr ? procedure_value(run) : profile_value(run);
  run.demand = machine_.next_demand(profile);
  more_channel_demands(run);
}

// Every channel after the first: its own profile on the rig's profile clock,
// shaped by the state machine like the first. A procedure drives only the
// first channel; the others play their profiles.
void RigLoop::more_channel_demands(RunState& run) noexcept {
  if (more_count_ == 0) return;
  const bool profile_mode = machine_.demand_mode() == DemandMode::kProfile;
  const double t_profile = run.profile_clock.profile_time_s(run.t_ns());
  for (std::size_t i = 0; i < more_count_; ++i) {
    const double profile = profile_mode ? more_channels_[i].profile->next(t_profile) : 0.0;
    run.more_demand[i] = machine_.next_channel_demand(i + 1, profile);
  }
}

double RigLoop::profile_value(RunState& run) noexcept {
  const double t_profile = run.profile_clock.profile_time_s(run.t_ns());
  const double value = profile_.next(t_profile);
  // Operator mode: at the profile's end the rig holds and waits for the operator.
  if (!safety_.auto_sequence && t_profile - run.profile_clock.first_s() >= profile_.raw().duration()) {
    machine_.profile_finished();
    events_.log_state_changes(machine_, run.tick, run.t_ns());
  }
  return value;
}

// One tick of the procedure; a trip of its own is logged as it happens and
// acts through the state machine on the next tick's check.
double RigLoop::procedure_value(RunState& run) noexcept {
  const double value = procedure_->next(run.record.sample, run.feedback);
  Event trip;
  if (procedure_->new_trip(trip)) {
    if (trip.action > run.worst_trip.action) run.worst_trip = trip;
    events_.log(loop_event(run.tick, run.t_ns(), machine_.state(), trip));
    run.procedure_trip = trip;
  }
  return value;
}

// The recovery when a cycle, pass or step ended, and at least every
// recovery_every_ticks while the procedure runs.
void RigLoop::offer_recovery(RunState& run) noexcept {
  if (recovery_sink_ == nullptr || (procedure_->finished() && !procedure_->recovery_due())) return;
  const bool periodic = recovery_every_ticks_ > 0 && run.tick - last_recovery_tick_ >= recovery_every_ticks_;
  if (!procedure_->recovery_due() && !periodic) return;
  procedure_->recovery(*recovery_);
  recovery_sink_->offer(*recovery_);
  last_recovery_tick_ = run.tick;
}

// ---- control + write

void RigLoop::control_and_write(RunState& run) {
  TelemetryRecord& r = run.record;
  if (run.valve_enabled) {
    controller_.update(run.demand, r.sample, r.command, r.controller);
    control_more_channels(run);
    stamp(TickStage::kControl);
    driver_.write(r.command);
    stamp(TickStage::kWrite);
    if (machine_.state() == SafetyState::kRunning) run.ever_ran = true;
  } else {
    // The driver holds its safe command (Driver::make_safe, the one place
    // it is defined); nothing is written, the record shows no command.
    r.controller.setpoint = run.demand;
    r.controller.measurement = run.feedback;
    for (std::size_t i = 0; i < more_count_; ++i) {
      r.more_channels[i].setpoint = run.more_demand[i];
      r.more_channels[i].measurement = r.sample.value[static_cast<std::size_t>(more_channels_[i].feedback_input)];
    }
  }
}

// Each channel after the first writes its own output of the tick's command.
void RigLoop::control_more_channels(RunState& run) noexcept {
  TelemetryRecord& r = run.record;
  for (std::size_t i = 0; i < more_count_; ++i) {
    more_channels_[i].controller->update(run.more_demand[i], r.sample, r.command, more_terms_);
    ChannelTerms& c = r.more_channels[i];
    c.setpoint = more_terms_.setpoint;
    c.measurement = more_terms_.measurement;
    c.output = more_terms_.output;
    c.saturated = more_terms_.saturated;
  }
}

// ---- hand-off

void RigLoop::hand_off(RunState& run) noexcept {
  TelemetryRecord& r = run.record;
  r.state = coarse_state(machine_.state(), run.ever_ran);
  r.safety_state = machine_.state();
  r.valve_enabled = run.valve_enabled;
  r.channel_count = static_cast<uint8_t>(1 + more_count_);
  r.event = record_event(run);
  if (procedure_ != nullptr) {
    r.procedure = procedure_->status();
    offer_recovery(run);
  }
  const bool timing_due = options_.timing_every_ticks > 0 && (run.tick + 1) % options_.timing_every_ticks == 0;
  emit(r, timing_due);  // its timing figures are those of the ticks before this one
  // The tick's compute ends when the publisher has the record: a hand-off
  // that waits is part of the tick, and of its overrun.
  const int64_t done_ns = clock_.now_ns();
  timing_.on_stage(TickStage::kHandOff, done_ns);
  run.deadline_ns = timing_.on_done(run.deadline_ns, run.woke_ns, done_ns);
  // What the next tick's sample is judged against.
  run.previous_t_ns = run.t_ns();
  run.previous_demand = run.demand;
  run.previous_command = run.valve_enabled ? r.command : Command{};
  run.valve_was_enabled = run.valve_enabled;
}

// The record's one event: the run's start, else this tick's worst new trip,
// else the operator's or signal's command.
Event RigLoop::record_event(const RunState& run) const noexcept {
  if (run.tick == 0) return Event{EventCode::kRunStarted, -1, 0.0};
  const DetectorResult& trips = detectors_.last();
  if (trips.new_count > 0) return trips.worst_new.event();
  return run.procedure_trip.code != EventCode::kNone ? run.procedure_trip : run.command_event;
}

void RigLoop::emit(TelemetryRecord& record, bool with_timing) noexcept {
  record.has_timing = with_timing;
  if (with_timing) record.timing = timing_.summary();
  if (!telemetry_.push(record)) ++dropped_;
}

// ---- end of run

RigLoop::Step RigLoop::decide_end(RunState& run) noexcept {
  const bool procedure_done = procedure_ != nullptr && procedure_->finished();
  if ((run.tick + 1 >= options_.max_ticks || procedure_done) && !run.run_length_reached) stop_at_run_length(run);
  if (procedure_ != nullptr && !procedure_done && procedure_->take_stop_due()) stop_at_block_end(run);
  // Operator mode ends when the operator has stopped the rig and then turned
  // the hydraulics off: the test is over and the rig is safe.
  const bool operator_done = !safety_.auto_sequence && run.operator_stopped && machine_.state() == SafetyState::kOff;
  if (operator_done && !run.stop_request_seen) run.end_event = Event{EventCode::kStopRequested, -1, 0.0};
  const bool finishing =
      run.run_length_reached || run.stop_request_seen || operator_done || (safety_.auto_sequence && run.ever_ran);
  const bool rig_safe = !machine_.valve_enabled() && machine_.state() != SafetyState::kStopping;
  const bool ends = finishing && rig_safe;
  if (ends && safety_.auto_sequence && machine_.hydraulics() != HydraulicsStage::kOff &&
      machine_.state() != SafetyState::kFaulted) {
    apply_command(kHydraulicsOffCommand, EventSource::kAutomatic, true, run);
  }
  events_.log_state_changes(machine_, run.tick, run.t_ns());
  return ends ? Step::kEndRun : Step::kCarryOn;
}

// The run's length reached: a controlled stop (ramp to hold, disarm), and
// the automatic sequence never starts the rig again.
void RigLoop::stop_at_run_length(RunState& run) noexcept {
  run.run_length_reached = true;
  commands_.run_ending();
  if (machine_.valve_enabled()) apply_command(kStopCommand, EventSource::kAutomatic, true, run);
}

// The block an operator asked to stop at has ended: a controlled stop, as
// the operator's own stop would be (in operator mode hydraulics off then
// ends the run; a start continues the procedure with the next block).
void RigLoop::stop_at_block_end(RunState& run) noexcept {
  const Event e{EventCode::kBlockEndStop, -1, static_cast<double>(procedure_->status().total_cycles)};
  events_.log(loop_event(run.tick, run.t_ns(), machine_.state(), e));
  run.operator_stopped = true;
  if (safety_.auto_sequence) commands_.run_ending();  // the automatic sequence does not start it again
  if (machine_.valve_enabled()) apply_command(kStopCommand, EventSource::kAutomatic, true, run);
}

// ---- after the last tick

LoopResult RigLoop::finish_run(RunState& run) noexcept {
  // A trip that held or stopped the rig makes the run a faulted one, even
  // when the stop itself was controlled.
  if (!run.ended_by_fault && run.worst_trip.action >= static_cast<uint8_t>(LimitAction::kHold)) {
    run.ended_by_fault = true;
    run.end_event = run.worst_trip;
  }
  const RigState end_state = run.ended_by_fault ? RigState::kFaulted : RigState::kStopped;

  // The closing record: why the run ended, and the final timing statistics.
  TelemetryRecord& closing = run.record;
  closing.tick = run.tick;
  closing.has_sample = false;
  closing.state = end_state;
  closing.safety_state = machine_.state();
  closing.valve_enabled = false;
  closing.event = run.end_event;
  emit(closing, true);
  EventRecord e = loop_event(run.tick, run.previous_t_ns, machine_.state(), run.end_event);
  e.source = run.end_event.code != EventCode::kStopRequested ? EventSource::kLoop
             : run.operator_stopped && !run.stop_request_seen ? EventSource::kOperator
                                                              : EventSource::kSignal;
  events_.log(e);

  LoopResult result;
  result.ticks = run.tick;
  result.final_state = end_state;
  result.final_safety_state = machine_.state();
  result.end_event = run.end_event;
  result.timing = timing_.summary();
  result.dropped_records = dropped_;
  result.dropped_events = events_.dropped();
  return result;
}

}  // namespace rigctl
