// Where the loop hands every event that must never be lost: state changes,
// limit trips, operator commands (accepted or refused), the run's start and
// end. Rare, fixed-size records; the event log (rt/comms/event_log.hpp) writes and
// fsyncs each one off the real-time path. Implementations never block.
#pragma once

#include <cstdint>

#include "rt/rig_state.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

enum class EventSource : uint8_t {
  kLoop,       // the loop itself: a detector, the profile, the driver
  kOperator,   // an authenticated operator command
  kAutomatic,  // the automatic sequence of `rigctl run` without an operator
  kSignal,     // SIGINT/SIGTERM
};

constexpr const char* to_string(EventSource s) {
  switch (s) {
    case EventSource::kLoop: return "loop";
    case EventSource::kOperator: return "operator";
    case EventSource::kAutomatic: return "auto";
    case EventSource::kSignal: return "signal";
  }
  return "unknown";
}

struct EventRecord {
  int64_t tick = 0;
  int64_t t_ns = 0;  // rig time of the tick
  SafetyState state = SafetyState::kFaulted;  // the state after the event
  Event event;
  SafetyState from = SafetyState::kFaulted;   // kStateChanged: the state before
  EventCode cause = EventCode::kNone;         // kStateChanged: what caused it
  EventSource source = EventSource::kLoop;
  uint64_t sequence = 0;                      // operator commands: the sender's sequence number
};

class EventSink {
 public:
  virtual ~EventSink() = default;
  // Returns false when the record could not be queued (counted by the loop).
  virtual bool push(const EventRecord& record) noexcept = 0;
};

}  // namespace rigctl
