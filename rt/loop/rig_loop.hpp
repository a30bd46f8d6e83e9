// The fixed-period control loop. One tick, each step a member function on
// the run's state (rt/loop/run_state.hpp):
//   wait      sleep to the absolute deadline, record the wake-up latency;
//             a stop request seen here ends the run at once if the valve is safe
//   read      driver.read fills the tick's sample
//   check     the limit detectors judge it against the previous tick's demand
//             and command; the state machine takes their action (a fault
//             makes the valve safe at once; without an operator an interlock
//             or a fault ends the run here, before anything is written)
//   commands  the command sources in order (rt/loop/command_sources.hpp):
//             a stop request, the operator's queue, the automatic sequence
//   demand    the profile (or a ramp to hold) through the state machine
//   control + write  controller.update, driver.write (or nothing: valve safe)
//   hand-off  one telemetry record into the sink; events went to the event
//             sink as they happened
//   end of run  at max_ticks a controlled stop; the run ends once the rig is
//             safe (and, without an operator, hydraulics off)
// Nothing on this path allocates, locks, logs or formats; events are codes
// that the publisher and event-log threads turn into text.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>

#include "rt/comms/event_sink.hpp"
#include "rt/comms/telemetry_sink.hpp"
#include "rt/control/controller.hpp"
#include "rt/control/setpoint_profile.hpp"
#include "rt/driver.hpp"
#include "rt/loop/command_sources.hpp"
#include "rt/loop/loop_events.hpp"
#include "rt/loop/run_state.hpp"
#include "rt/loop_clock.hpp"
#include "rt/procedure/procedure_runner.hpp"
#include "rt/procedure/recovery_sink.hpp"
#include "rt/safety/limit_detectors.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/safety/rig_state_machine.hpp"
#include "rt/spsc_queue.hpp"
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

// A control channel after the first of a rig with several actuators (a
// two-poster road simulator): its own controller (which reads its own
// feedback input and writes its own output of the shared Command), its own
// profile, and the input arm holds it at. The limit detectors and the state
// machine act on the whole rig: one interlock makes every output safe.
struct ControlChannel {
  Controller* controller = nullptr;
  FilteredProfile* profile = nullptr;
  int feedback_input = 0;
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
  // The rig as `rigctl run` assembles it (tools/run/rig_assembly.hpp): its
  // limit detectors and the state machine's settings.
  RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, LimitDetectors detectors,
          TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options, const SafetyOptions& safety);

  // Optional inputs, set before run(): authenticated operator commands (the
  // LCM receiver pushes them) and the durable event log.
  void set_operator_commands(SpscQueue<OperatorCommand>* commands) { commands_.attach_operator_queue(commands); }
  void set_event_sink(EventSink* events) { events_.attach(events); }
  // A test procedure gives the demand instead of the profile, its trips act
  // like the detectors', its end ends the run; its recoveries go to
  // `recovery` (may be nullptr) at every cycle, pass and step end and at
  // least every recovery_every_ticks.
  void set_procedure(ProcedureRunner* procedure, RecoverySink* recovery, int64_t recovery_every_ticks);
  // The rig's control channels after the first (the constructor's controller
  // and profile are channel 1), each run every tick after the first; at most
  // kMaxChannels - 1 (std::invalid_argument otherwise). Copied into a fixed
  // array: the tick walks it without allocating.
  void set_more_channels(std::span<const ControlChannel> channels);

  // Runs until the rig is stopped (max_ticks or stop_requested: a controlled
  // stop) or faulted (automatic sequence). stop_requested is set from a
  // signal handler. The driver is made safe on every way out.
  LoopResult run(const std::atomic<bool>& stop_requested);

  const TimingStats& timing() const { return timing_; }
  const RigStateMachine& machine() const { return machine_; }

 private:
  // Whether the run goes on after a step.
  enum class Step : uint8_t { kCarryOn, kEndRun };

  void begin_run(RunState& run) noexcept;
  // The tick's steps, in order.
  void wait(RunState& run) noexcept;
  Step notice_stop_request(const std::atomic<bool>& stop_requested, RunState& run) noexcept;
  Step read(RunState& run);
  Step check(RunState& run) noexcept;
  void take_commands(RunState& run) noexcept;
  void demand(RunState& run) noexcept;
  void control_and_write(RunState& run);
  void hand_off(RunState& run) noexcept;
  // The step just done ends now (TimingStats::on_stage).
  void stamp(TickStage stage) noexcept { timing_.on_stage(stage, clock_.now_ns()); }
  Step decide_end(RunState& run) noexcept;
  LoopResult finish_run(RunState& run) noexcept;

  // Parts of the steps.
  const DetectorResult& judge_limits(RunState& run) noexcept;
  Step step_state_machine(const DetectorResult& trips, RunState& run) noexcept;
  CommandResult apply_command(const OperatorCommand& c, EventSource source, bool log_refusal, RunState& run) noexcept;
  void on_accepted(const OperatorCommand& c, EventSource source, const CommandResult& r, RunState& run) noexcept;
  void log_command(const OperatorCommand& c, EventSource source, const CommandResult& r, RunState& run) noexcept;
  double profile_value(RunState& run) noexcept;
  Event record_event(const RunState& run) const noexcept;
  void stop_at_run_length(RunState& run) noexcept;
  void stop_at_block_end(RunState& run) noexcept;
  void emit(TelemetryRecord& record, bool with_timing) noexcept;
  double procedure_value(RunState& run) noexcept;
  void more_channel_demands(RunState& run) noexcept;
  void control_more_channels(RunState& run) noexcept;
  void offer_recovery(RunState& run) noexcept;

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
  CommandSources commands_;
  LoopEvents events_;
  int64_t dropped_ = 0;  // telemetry records the sink refused
  ProcedureRunner* procedure_ = nullptr;
  RecoverySink* recovery_sink_ = nullptr;
  int64_t recovery_every_ticks_ = 0;
  int64_t last_recovery_tick_ = 0;
  std::unique_ptr<ProcedureRecovery> recovery_;  // the hand-off's scratch, allocated before the run
  std::array<ControlChannel, kMaxChannels - 1> more_channels_{};  // channel i at i - 1
  std::size_t more_count_ = 0;
  ControllerTerms more_terms_{};  // scratch for a channel's full terms; the record keeps their brief
};

}  // namespace rigctl
