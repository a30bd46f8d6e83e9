#include "rt/loop/rig_loop.hpp"

#include <limits>

namespace rigctl {

namespace {

StateMachineConfig with_period(StateMachineConfig c, int64_t period_ns) {
  c.period_s = static_cast<double>(period_ns) * 1e-9;
  return c;
}

// What `rigctl run` does without an operator, each command as soon as the
// state machine allows it.
constexpr OperatorCommandKind kAutoSequence[] = {OperatorCommandKind::kReset, OperatorCommandKind::kHydraulicsLow,
                                                 OperatorCommandKind::kHydraulicsHigh, OperatorCommandKind::kArm,
                                                 OperatorCommandKind::kStart};
constexpr std::size_t kAutoSteps = sizeof kAutoSequence / sizeof kAutoSequence[0];

// Operator commands handled per tick at most: a flood cannot stretch a tick.
constexpr int kMaxCommandsPerTick = 8;

// The loop as it was before the state machine (tests, benchmarks, the
// hidden-effect generator): the profile from tick 0 as configured and the
// run ending at max_ticks without a ramp. Infinite rates make the demand
// shaper pass everything through; `rigctl run` configures real ones.
SafetyOptions unshaped() {
  SafetyOptions s;
  s.machine.hold_deceleration = std::numeric_limits<double>::infinity();
  s.machine.setpoint_rate = std::numeric_limits<double>::infinity();
  return s;
}

}  // namespace

RigLoop::RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, const LimitCheck& limits,
                 TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options)
    : RigLoop(driver, controller, profile,
              LimitDetectors::from_limit_check(limits, static_cast<double>(options.period_ns) * 1e-9), telemetry,
              clock, options, unshaped()) {}

RigLoop::RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, LimitDetectors detectors,
                 TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options, const SafetyOptions& safety)
    : driver_(driver), controller_(controller), profile_(profile), detectors_(std::move(detectors)),
      telemetry_(telemetry), clock_(clock), options_(options), safety_(safety),
      machine_(with_period(safety.machine, options.period_ns)), timing_(options.period_ns, options.overrun_policy) {}

void RigLoop::emit(TelemetryRecord& record, bool with_timing) noexcept {
  record.has_timing = with_timing;
  if (with_timing) record.timing = timing_.summary();
  if (!telemetry_.push(record)) ++dropped_;
}

void RigLoop::log_event(const EventRecord& e) noexcept {
  if (events_ != nullptr && !events_->push(e)) ++dropped_events_;
}

void RigLoop::log_changes(int64_t tick, int64_t t_ns) noexcept {
  for (; changes_logged_ < machine_.change_count(); ++changes_logged_) {
    const StateChange& c = machine_.changes()[changes_logged_];
    EventRecord e;
    e.tick = tick;
    e.t_ns = t_ns;
    e.state = c.to;
    e.from = c.from;
    e.cause = c.cause;
    e.event = Event{EventCode::kStateChanged, -1, static_cast<double>(c.from), static_cast<uint8_t>(c.to), 0};
    log_event(e);
  }
}

RigState RigLoop::coarse_state() const noexcept {
  switch (machine_.state()) {
    case SafetyState::kRunning:
    case SafetyState::kHolding: return RigState::kRunning;
    case SafetyState::kStopping: return RigState::kStopping;
    case SafetyState::kFaulted: return ever_ran_ ? RigState::kFaulted : RigState::kStarting;
    default: return ever_ran_ ? RigState::kStopped : RigState::kStarting;
  }
}

LoopResult RigLoop::run(const std::atomic<bool>& stop_requested) {
  LoopResult result;
  TelemetryRecord record;
  controller_.reset();
  profile_.reset();
  machine_.power_on();
  ever_ran_ = false;
  frozen_ns_ = 0;
  const int feedback = safety_.feedback_input >= 0 ? safety_.feedback_input
                                                   : (options_.start_from_input >= 0 ? options_.start_from_input : 0);
  std::size_t next_auto = safety_.auto_sequence ? 0 : kAutoSteps;

  int64_t deadline = clock_.now_ns();
  int64_t tick = 0;
  Event end_event{EventCode::kProfileFinished, -1, 0.0};
  Event worst_trip{};  // the most severe trip of the run (hold or worse makes the run count as faulted)
  bool ended_by_fault = false;
  bool stop_seen = false, stop_applied = false, end_stop_applied = false;
  // Operator mode ends when the operator has stopped the rig and then turned
  // the hydraulics off: the test is over and the rig is safe.
  bool operator_stopped = false;
  bool valve_was_enabled = false;
  double last_demand = 0.0;
  Command last_command{};
  Event tick_event{};

  // One command through the state machine, with its consequences for the
  // detectors, the controller and the profile, and its event.
  auto command = [&](OperatorCommand c, EventSource source, int64_t t_ns, bool log_refusal) {
    const CommandResult r = machine_.apply(c);
    if (r.accepted) {
      if (r.reset_latches) {
        detectors_.clear_latches();
        worst_trip = Event{};
      }
      if (c.kind == OperatorCommandKind::kArm) controller_.reset();  // take over the valve with a fresh integrator
      if (source == EventSource::kOperator && c.kind == OperatorCommandKind::kStop) operator_stopped = true;
      if (c.kind == OperatorCommandKind::kStart) operator_stopped = false;  // a new test after a re-arm
      if (c.kind == OperatorCommandKind::kStart) {
        // The profile from its beginning: its clock restarts at the run's first sample time.
        profile_.reset();
        frozen_ns_ = t_ns - first_t_ns_;
        if (options_.start_from_input >= 0) {
          profile_.start_from(record.sample.value[static_cast<std::size_t>(options_.start_from_input)]);
        }
      }
    }
    if (r.accepted || log_refusal) {
      EventRecord e;
      e.tick = tick;
      e.t_ns = t_ns;
      e.state = machine_.state();
      e.source = source;
      e.sequence = c.sequence;
      e.event = r.accepted ? Event{EventCode::kCommandAccepted, -1, c.value, static_cast<uint8_t>(c.kind), 0}
                           : Event{EventCode::kCommandRejected, static_cast<int16_t>(c.kind), c.value,
                                   static_cast<uint8_t>(r.reason), 0};
      log_event(e);
      if (source == EventSource::kOperator || source == EventSource::kSignal) tick_event = e.event;
    }
    log_changes(tick, t_ns);  // the state change right after the command that caused it
    return r;
  };

  try {
    for (;; ++tick) {
      clock_.sleep_until(deadline);
      const int64_t start = clock_.now_ns();
      timing_.on_wake(deadline, start);

      if (stop_requested.load(std::memory_order_relaxed) && !stop_seen) {
        stop_seen = true;
        end_event = Event{EventCode::kStopRequested, -1, 0.0};
        if (!machine_.valve_enabled()) break;  // nothing to ramp: the rig is already safe
      }

      record = TelemetryRecord{};
      record.tick = tick;
      tick_event = Event{};
      if (!driver_.read(record.sample)) {
        end_event = Event{EventCode::kDriverReadFailed, -1, 0.0};
        ended_by_fault = true;
        break;
      }
      const int64_t t_ns = record.sample.t_ns;
      if (tick == 0) {
        first_t_ns_ = prev_t_ns_ = t_ns;
        EventRecord e;
        e.t_ns = t_ns;
        e.state = machine_.state();
        e.event = Event{EventCode::kRunStarted, -1, 0.0};
        log_event(e);
      }

      // Limit detectors, on what the previous tick commanded.
      DetectorInputs din;
      din.sample = &record.sample;
      din.now_ns = start;
      din.demand = last_demand;
      din.command = &last_command;
      din.valve_driven = machine_.valve_enabled();
      din.overruns = timing_.overruns();
      const DetectorResult& trips = detectors_.check(din);
      const std::size_t kept = trips.new_count < kMaxTripsPerTick ? trips.new_count : kMaxTripsPerTick;
      for (std::size_t i = 0; i < kept; ++i) {
        const Event ev = trips.new_trips[i].event();
        if (ev.action > worst_trip.action) worst_trip = ev;
        EventRecord e;
        e.tick = tick;
        e.t_ns = t_ns;
        e.state = machine_.state();
        e.event = ev;
        log_event(e);
      }

      MachineInputs in;
      in.limit_action = trips.action;
      in.faults_present = trips.faults_present;
      in.feedback_valid = !trips.feedback_invalid;
      in.feedback = record.sample.value[static_cast<std::size_t>(feedback)];
      changes_logged_ = 0;
      const SafetyState before = machine_.state();
      machine_.begin_tick(in, worst_trip.code);
      if (machine_.state() == SafetyState::kFaulted && before != SafetyState::kFaulted) {
        driver_.make_safe();  // a fault puts the valve to its safe command at once
        valve_was_enabled = false;
      }
      // Without an operator an interlock ends the run on this tick, before
      // anything is written (today's behaviour of `rigctl run`).
      if (safety_.auto_sequence && trips.action == LimitAction::kInterlock) {
        log_changes(tick, t_ns);
        end_event = worst_trip.code != EventCode::kNone ? worst_trip : trips.worst_new.event();
        ended_by_fault = true;
        break;
      }
      if (safety_.auto_sequence && machine_.state() == SafetyState::kFaulted && before != SafetyState::kFaulted) {
        log_changes(tick, t_ns);
        const StateChange& last = machine_.changes()[machine_.change_count() - 1];
        end_event = Event{last.cause, -1, 0.0};
        ended_by_fault = true;
        break;
      }

      // Commands: a stop request, the operator's, the automatic sequence.
      if (stop_seen && !stop_applied) {
        stop_applied = true;
        command(OperatorCommand{OperatorCommandKind::kStop, 0.0, 0}, EventSource::kSignal, t_ns, true);
      }
      if (commands_ != nullptr) {
        OperatorCommand c;
        for (int n = 0; n < kMaxCommandsPerTick && commands_->try_pop(c); ++n) command(c, EventSource::kOperator, t_ns, true);
      }
      while (next_auto < kAutoSteps && !stop_seen && !end_stop_applied) {
        const OperatorCommand c{kAutoSequence[next_auto], 0.0, 0};
        if (!command(c, EventSource::kAutomatic, t_ns, false).accepted) break;  // not yet: retried next tick
        ++next_auto;
      }
      log_changes(tick, t_ns);

      // Demand and control.
      const bool enabled = machine_.valve_enabled();
      if (!enabled && valve_was_enabled) driver_.make_safe();
      if (tick > 0 && !machine_.profile_clock_running()) frozen_ns_ += t_ns - prev_t_ns_;
      double demand = last_demand;
      if (enabled) {
        double profile = 0.0;
        if (machine_.demand_mode() == DemandMode::kProfile) {
          const double t_profile = static_cast<double>(t_ns - frozen_ns_) * 1e-9;
          profile = profile_.next(t_profile);
          if (!safety_.auto_sequence &&
              t_profile - static_cast<double>(first_t_ns_) * 1e-9 >= profile_.raw().duration()) {
            machine_.profile_finished();  // operator mode: hold at the end, wait for the operator
            log_changes(tick, t_ns);
          }
        }
        demand = machine_.next_demand(profile);
        controller_.update(demand, record.sample, record.command, record.controller);
        driver_.write(record.command);
        if (machine_.state() == SafetyState::kRunning) ever_ran_ = true;
      } else {
        // The driver holds its safe command (Driver::make_safe, the one place
        // it is defined); nothing is written, the record shows no command.
        record.controller.setpoint = demand;
        record.controller.measurement = in.feedback;
      }
      record.state = coarse_state();
      record.safety_state = machine_.state();
      record.valve_enabled = enabled;
      if (tick == 0) {
        record.event = Event{EventCode::kRunStarted, -1, 0.0};
      } else if (trips.new_count > 0) {
        record.event = trips.worst_new.event();
      } else {
        record.event = tick_event;
      }

      const int64_t end = clock_.now_ns();
      deadline = timing_.on_done(deadline, start, end);
      const bool timing_due = options_.timing_every_ticks > 0 && (tick + 1) % options_.timing_every_ticks == 0;
      emit(record, timing_due);
      last_demand = demand;
      last_command = enabled ? record.command : Command{};
      valve_was_enabled = enabled;
      prev_t_ns_ = t_ns;

      // The run's length reached: a controlled stop (ramp to hold, disarm).
      if (tick + 1 >= options_.max_ticks && !end_stop_applied) {
        end_stop_applied = true;
        if (machine_.valve_enabled()) command(OperatorCommand{OperatorCommandKind::kStop, 0.0, 0}, EventSource::kAutomatic, t_ns, true);
      }
      const bool operator_done = !safety_.auto_sequence && operator_stopped && machine_.state() == SafetyState::kOff;
      if (operator_done && !stop_seen) end_event = Event{EventCode::kStopRequested, -1, 0.0};
      const bool finishing = end_stop_applied || stop_seen || operator_done || (safety_.auto_sequence && ever_ran_);
      if (finishing && !machine_.valve_enabled() && machine_.state() != SafetyState::kStopping) {
        if (safety_.auto_sequence && machine_.hydraulics() != HydraulicsStage::kOff &&
            machine_.state() != SafetyState::kFaulted) {
          command(OperatorCommand{OperatorCommandKind::kHydraulicsOff, 0.0, 0}, EventSource::kAutomatic, t_ns, true);
        }
        log_changes(tick, t_ns);
        ++tick;
        break;
      }
      log_changes(tick, t_ns);
    }
  } catch (...) {
    // Drivers may throw on a broken device; the outputs go safe before the
    // exception leaves the loop.
    driver_.make_safe();
    throw;
  }
  driver_.make_safe();

  // A trip that held or stopped the rig makes the run a faulted one, even
  // when the stop itself was controlled.
  if (!ended_by_fault && worst_trip.action >= static_cast<uint8_t>(LimitAction::kHold)) {
    ended_by_fault = true;
    end_event = worst_trip;
  }
  const RigState end_state = ended_by_fault ? RigState::kFaulted : RigState::kStopped;

  // The closing record: why the run ended, and the final timing statistics.
  record.tick = tick;
  record.has_sample = false;
  record.state = end_state;
  record.safety_state = machine_.state();
  record.valve_enabled = false;
  record.event = end_event;
  emit(record, true);
  {
    EventRecord e;
    e.tick = tick;
    e.t_ns = prev_t_ns_;
    e.state = machine_.state();
    e.event = end_event;
    e.source = end_event.code != EventCode::kStopRequested ? EventSource::kLoop
               : operator_stopped && !stop_seen               ? EventSource::kOperator
                                                              : EventSource::kSignal;
    log_event(e);
  }

  result.ticks = tick;
  result.final_state = end_state;
  result.final_safety_state = machine_.state();
  result.end_event = end_event;
  result.timing = timing_.summary();
  result.dropped_records = dropped_;
  result.dropped_events = dropped_events_;
  return result;
}

}  // namespace rigctl
