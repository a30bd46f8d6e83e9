// Where the state machine's commands come from on each tick, in order of
// precedence: a stop request (SIGINT/SIGTERM), the operator's authenticated
// commands (the receiver's queue) and the automatic sequence of `rigctl run`
// without an operator. The loop asks each source in turn for commands until
// it has none left this tick and tells it the state machine's answer; the
// source decides what that answer means for it (the automatic sequence waits
// for the next tick after a refusal). The sources belong to the loop thread:
// no allocation, no locks.
#pragma once

#include <array>
#include <cstddef>

#include "rt/comms/event_sink.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/spsc_queue.hpp"

namespace rigctl {

class CommandSource {
 public:
  CommandSource(EventSource origin, bool logs_refusals) noexcept : origin_(origin), logs_refusals_(logs_refusals) {}
  virtual ~CommandSource() = default;
  CommandSource(const CommandSource&) = delete;
  CommandSource& operator=(const CommandSource&) = delete;

  // Once per tick, before the first next().
  virtual void begin_tick() noexcept {}
  // The next command this tick; false: nothing (more) this tick.
  virtual bool next(OperatorCommand& command) noexcept = 0;
  // The state machine's answer to the command next() gave last.
  virtual void answered(bool accepted) noexcept { (void)accepted; }

  // Who sends the commands (the event log names it) and whether a refusal is
  // logged: for the operator and a signal it is an answer they must see.
  EventSource origin() const noexcept { return origin_; }
  bool logs_refusals() const noexcept { return logs_refusals_; }

 private:
  EventSource origin_;
  bool logs_refusals_;
};

// SIGINT/SIGTERM: one controlled stop, on the tick the request is seen.
class StopRequestSource final : public CommandSource {
 public:
  StopRequestSource() noexcept : CommandSource(EventSource::kSignal, true) {}
  void restart() noexcept { requested_ = given_ = false; }
  void request() noexcept { requested_ = true; }
  bool next(OperatorCommand& command) noexcept override;

 private:
  bool requested_ = false;
  bool given_ = false;
};

// The operator's commands, authenticated by the receiver before they reach
// the queue. A bounded number per tick: a flood cannot stretch a tick; the
// rest wait in the queue for the next ticks.
class OperatorQueueSource final : public CommandSource {
 public:
  static constexpr int kMaxPerTick = 8;

  OperatorQueueSource() noexcept : CommandSource(EventSource::kOperator, true) {}
  void attach(SpscQueue<OperatorCommand>* queue) noexcept { queue_ = queue; }
  void begin_tick() noexcept override { taken_ = 0; }
  bool next(OperatorCommand& command) noexcept override;

 private:
  SpscQueue<OperatorCommand>* queue_ = nullptr;  // nullptr: no operator
  int taken_ = 0;                                // commands taken this tick
};

// `rigctl run` without an operator: reset, hydraulics low, high, arm and
// start, each as soon as the state machine accepts it. A refused step is
// tried again on the next tick and its refusal is not logged: "not yet"
// (pressure still rising) is no error. Once the run is ending the sequence
// is over: it never starts the rig again.
class AutomaticSequence final : public CommandSource {
 public:
  static constexpr std::array<OperatorCommandKind, 5> kSteps = {
      OperatorCommandKind::kReset, OperatorCommandKind::kHydraulicsLow, OperatorCommandKind::kHydraulicsHigh,
      OperatorCommandKind::kArm, OperatorCommandKind::kStart};

  AutomaticSequence() noexcept : CommandSource(EventSource::kAutomatic, false) {}
  // enabled: this run has no operator; off, the sequence gives nothing.
  void restart(bool enabled) noexcept;
  void end() noexcept { next_step_ = kSteps.size(); }
  void begin_tick() noexcept override { refused_this_tick_ = false; }
  bool next(OperatorCommand& command) noexcept override;
  void answered(bool accepted) noexcept override;

 private:
  std::size_t next_step_ = kSteps.size();
  bool refused_this_tick_ = false;
};

// The loop's sources in their order of precedence: a stop request goes in
// before the operator's commands, and both before the automatic sequence.
class CommandSources {
 public:
  CommandSources() = default;
  CommandSources(const CommandSources&) = delete;
  CommandSources& operator=(const CommandSources&) = delete;

  void attach_operator_queue(SpscQueue<OperatorCommand>* queue) noexcept { operator_queue_.attach(queue); }
  // A new run: no stop requested; the automatic sequence from its first step
  // when the run has no operator.
  void restart(bool automatic_sequence) noexcept {
    stop_request_.restart();
    automatic_.restart(automatic_sequence);
  }
  // A stop was requested: it goes in on this tick, and the run is ending.
  void request_stop() noexcept {
    stop_request_.request();
    automatic_.end();
  }
  // The run is ending (its length is reached): the rig is not started again.
  void run_ending() noexcept { automatic_.end(); }

  // Every command of this tick, in order, through `apply(command, source)`,
  // which returns whether the state machine accepted it.
  template <class Apply>
  void take(Apply&& apply) {
    for (CommandSource* source : in_order_) {
      source->begin_tick();
      OperatorCommand command;
      while (source->next(command)) source->answered(apply(command, *source));
    }
  }

 private:
  StopRequestSource stop_request_;
  OperatorQueueSource operator_queue_;
  AutomaticSequence automatic_;
  const std::array<CommandSource*, 3> in_order_{&stop_request_, &operator_queue_, &automatic_};
};

}  // namespace rigctl
