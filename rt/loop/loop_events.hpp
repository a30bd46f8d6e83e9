// The loop's side of the event log: fixed-size records into the EventSink
// (which never blocks; a refused record is counted), and each state change
// of the machine logged once, right after what caused it (a trip, a command,
// a settled stop), so the log reads in cause-then-effect order.
#pragma once

#include <cstddef>
#include <cstdint>

#include "rt/comms/event_sink.hpp"
#include "rt/safety/rig_state_machine.hpp"

namespace rigctl {

// An event of the loop itself (source kLoop): a trip, the run's start, why it ended.
inline EventRecord loop_event(int64_t tick, int64_t t_ns, SafetyState state, const Event& event) noexcept {
  EventRecord e;
  e.tick = tick;
  e.t_ns = t_ns;
  e.state = state;
  e.event = event;
  return e;
}

class LoopEvents {
 public:
  void attach(EventSink* sink) noexcept { sink_ = sink; }

  void log(const EventRecord& e) noexcept {
    if (sink_ != nullptr && !sink_->push(e)) ++dropped_;
  }
  // The machine's begin_tick starts its list of changes afresh: so does the log.
  void begin_tick() noexcept { changes_logged_ = 0; }
  // The machine's state changes not logged yet this tick.
  void log_state_changes(const RigStateMachine& machine, int64_t tick, int64_t t_ns) noexcept;

  int64_t dropped() const noexcept { return dropped_; }

 private:
  EventSink* sink_ = nullptr;  // nullptr: no event log (tests, benchmarks)
  int64_t dropped_ = 0;
  std::size_t changes_logged_ = 0;
};

}  // namespace rigctl
