// What the loop does when its bounded queue to a consumer thread (telemetry
// publisher, event log) is full. The choice follows the loop's clock:
//
// * A paced run (wall clock, real hardware or the simulated plant in real
//   time) has a deadline every period. Waiting for a consumer would stall the
//   tick and with it the rig, so a full queue drops the record, counts it and
//   the count is published (kDrop).
// * A run in simulated time (--fast, make-run, replays, the bench's closed
//   loops) has no deadline: simulated time stands still while the loop waits.
//   Dropping there would be data loss that nothing forces, so the loop waits
//   for the consumer to make room (backpressure, kWait).
#pragma once

#include <cstdint>

namespace rigctl {

enum class QueueFullPolicy : uint8_t {
  kDrop,  // never block the producer; drop and count
  kWait,  // wait for the consumer; nothing is dropped while it runs
};

constexpr const char* to_string(QueueFullPolicy p) {
  switch (p) {
    case QueueFullPolicy::kDrop: return "drop";
    case QueueFullPolicy::kWait: return "wait";
  }
  return "unknown";
}

}  // namespace rigctl
