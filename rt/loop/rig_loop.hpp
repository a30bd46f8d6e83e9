// The fixed-period control loop. One tick:
//   sleep to the absolute deadline -> driver.read -> limit detectors
//   -> state machine (limit actions, operator and automatic commands)
//   -> demand (profile, or a ramp to hold) -> controller -> driver.write
//   -> telemetry record into a lock-free queue, events into the event sink
// Nothing on this path allocates, locks, logs or formats; events are codes
// that the publisher and event-log threads turn into text.
#pragma once

#include <atomic>
#include <cstdint>

#include "rt/driver.hpp"
#include "rt/control/controller.hpp"
#include "rt/comms/event_sink.hpp"
#include "rt/safety/limit_check.hpp"
#include "rt/safety/limit_detectors.hpp"
#include "rt/loop_clock.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/safety/rig_state_machine.hpp"
#include "rt/control/setpoint_profile.hpp"
#include "rt/spsc_queue.hpp"
#include "rt/comms/telemetry_sink.hpp"
#include "rt/timing_stats.hpp"

namespace rigctl {

struct LoopOptions {
  int64_t period_ns = 2'500'000;
  OverrunPolicy overrun_policy = OverrunPolicy::kSkip;
  // Run length: after this many ticks the loop stops the rig in the
  // controlled way (ramp to hold, disarm) and ends.
  int64_t max_ticks = 0;
  int64_t timing_every_ticks = 400;  // publish timing statistics this often (1 s at 2.5 ms)
  int start_from_input = -1;  // >= 0: the profile starts from this input's first value (bumpless start)
};

struct SafetyOptions {
  StateMachineConfig machine;  // period_s is taken from LoopOptions
  // No operator (`rigctl run`): reset, hydraulics low, high, arm and start as
  // soon as each is allowed, a controlled stop at max_ticks, and the run ends
  // when the rig is stopped or faulted. Off: only operator commands move the
  // rig; the run ends at a stop request once the valve is safe, or when an
  // operator stop has been followed by hydraulics off (state off).
  bool auto_sequence = true;
  int feedback_input = -1;  // the controlled input: arm holds here; -1 = input 0
};

struct LoopResult {
  int64_t ticks = 0;
  RigState final_state = RigState::kStopped;
  SafetyState final_safety_state = SafetyState::kOff;
  Event end_event;  // why the run ended
  TimingSummary timing;
  int64_t dropped_records = 0;
  int64_t dropped_events = 0;  // event sink refused (should be 0)
};

class RigLoop {
 public:
  // Today's interface: the LimitCheck as interlock detectors, the automatic
  // sequence, no operator.
  RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, const LimitCheck& limits,
          TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options);
  RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, LimitDetectors detectors,
          TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options, const SafetyOptions& safety);

  // Optional inputs, set before run(): authenticated operator commands (the
  // LCM receiver pushes them) and the durable event log.
  void set_operator_commands(SpscQueue<OperatorCommand>* commands) { commands_ = commands; }
  void set_event_sink(EventSink* events) { events_ = events; }

  // Runs until the rig is stopped (max_ticks or stop_requested: a controlled
  // stop) or faulted (automatic sequence). stop_requested is set from a
  // signal handler. The driver is made safe on every way out.
  LoopResult run(const std::atomic<bool>& stop_requested);

  const TimingStats& timing() const { return timing_; }
  const RigStateMachine& machine() const { return machine_; }

 private:
  void emit(TelemetryRecord& record, bool with_timing) noexcept;
  void log_event(const EventRecord& e) noexcept;
  void log_changes(int64_t tick, int64_t t_ns) noexcept;
  CommandResult command(const OperatorCommand& c, EventSource source, int64_t tick, int64_t t_ns, bool log_refusal) noexcept;
  RigState coarse_state() const noexcept;

  Driver& driver_;
  Controller& controller_;
  FilteredProfile& profile_;
  LimitDetectors detectors_;
  TelemetrySink& telemetry_;
  LoopClock& clock_;
  LoopOptions options_;
  SafetyOptions safety_;
  RigStateMachine machine_;
  TimingStats timing_;
  SpscQueue<OperatorCommand>* commands_ = nullptr;
  EventSink* events_ = nullptr;
  int64_t dropped_ = 0;
  int64_t dropped_events_ = 0;
  std::size_t changes_logged_ = 0;
  bool ever_ran_ = false;
  // Profile clock: sample time minus the time the profile was not running.
  int64_t first_t_ns_ = 0, prev_t_ns_ = 0, frozen_ns_ = 0;
  bool start_pending_ = false;
};

}  // namespace rigctl
