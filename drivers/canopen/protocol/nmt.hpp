// NMT node control and NMT error control (heartbeat), CiA 301.
//
// NMT command: COB-ID 0x000, 2 bytes [command specifier, node id (0 = all)].
// Heartbeat:   COB-ID 0x700+node, 1 byte [state]; the boot-up message is a
//              heartbeat with state 0x00, sent once when the node leaves
//              initialisation. Bit 7 of the state byte is the node-guarding
//              toggle bit, reserved (0) in heartbeats: decoding ignores it.
//
// Times are int64 nanoseconds on any monotonic clock, always passed in by the
// caller: nothing here reads a clock, sleeps or allocates.
#pragma once

#include <cstdint>
#include <optional>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"

namespace rigctl::canopen {

enum class NmtCommand : uint8_t {
  kStart = 0x01,                // to operational
  kStop = 0x02,                 // to stopped
  kEnterPreOperational = 0x80,  // to pre-operational
  kResetNode = 0x81,            // reset application (and communication)
  kResetCommunication = 0x82,   // reset communication
};

enum class NmtState : uint8_t {
  kBootUp = 0x00,
  kStopped = 0x04,
  kOperational = 0x05,
  kPreOperational = 0x7F,
};

const char* nmt_state_name(NmtState s);
const char* nmt_command_name(NmtCommand c);

// NMT command to `node` (1..127), or to all nodes with node 0.
CanFrame encode_nmt(NmtCommand command, uint8_t node);

struct NmtMessage {
  NmtCommand command = NmtCommand::kStart;
  uint8_t node = 0;  // 0: all nodes
};
// For the simulated valve: COB-ID 0x000, length 2, a defined command and a node id 0..127.
Malformed decode_nmt(const CanFrame& frame, NmtMessage& out);

// Heartbeat (or, with kBootUp, the boot-up message) of `node`.
CanFrame encode_heartbeat(uint8_t node, NmtState state);

struct Heartbeat {
  uint8_t node = 0;
  NmtState state = NmtState::kBootUp;
};
// COB-ID 0x700+node (1..127), length 1, one of the four states.
Malformed decode_heartbeat(const CanFrame& frame, Heartbeat& out);

// Object 0x1016 sub 1..n (consumer heartbeat time), UNSIGNED32:
// bits 16..23 node id of the producer, bits 0..15 time in ms. 0x1017 (producer
// heartbeat time) is UNSIGNED16 ms.
constexpr uint32_t consumer_heartbeat_entry(uint8_t node, uint16_t time_ms) {
  return (static_cast<uint32_t>(node) << 16) | time_ms;
}

// Watches the heartbeat of one node. Per CiA 301, monitoring starts with the
// first heartbeat received: until then the node is kNeverSeen and never times
// out (the driver bounds start-up with its own deadline). A node is alive while
// now - last heartbeat <= consumer time; a heartbeat exactly `consumer time`
// after the previous one is in time, one nanosecond later is not. A consumer
// time of 0 disables the timeout.
class HeartbeatConsumer {
 public:
  enum class Status : uint8_t { kNeverSeen, kAlive, kTimedOut };
  enum class Event : uint8_t {
    kNone,
    kFirstSeen,               // first heartbeat (or boot-up) from this node
    kStateChanged,            // alive, and the reported NMT state changed
    kRecovered,               // a heartbeat after a timeout
    kTimedOut,                // poll(): no heartbeat within the consumer time (reported once)
    kBootUp,                  // boot-up message while not operational (expected after a reset we asked for)
    kResetAfterOperational,   // boot-up message after the node had been operational: it reset by itself
  };

  HeartbeatConsumer(uint8_t node, int64_t consumer_time_ns) : node_(node), consumer_time_ns_(consumer_time_ns) {}

  // Feeds one decoded heartbeat of any node; heartbeats of other nodes are
  // ignored (kNone).
  Event on_heartbeat(const Heartbeat& hb, int64_t now_ns);
  // Checks the timeout at `now_ns`; kTimedOut once, on the transition.
  Event poll(int64_t now_ns);

  uint8_t node() const { return node_; }
  Status status() const { return status_; }
  bool alive() const { return status_ == Status::kAlive; }
  NmtState last_state() const { return last_state_; }
  int64_t last_heartbeat_ns() const { return last_ns_; }  // valid once seen
  int64_t consumer_time_ns() const { return consumer_time_ns_; }
  // Sticky until clear_reset(): a boot-up came after the node was operational.
  bool reset_after_operational() const { return reset_after_operational_; }
  void clear_reset() { reset_after_operational_ = false; }
  uint32_t timeouts() const { return timeouts_; }
  uint32_t boot_ups() const { return boot_ups_; }
  // Back to kNeverSeen (e.g. after the driver resets the node on purpose).
  void reset();

 private:
  uint8_t node_;
  int64_t consumer_time_ns_;
  Status status_ = Status::kNeverSeen;
  NmtState last_state_ = NmtState::kBootUp;
  int64_t last_ns_ = 0;
  bool operational_since_boot_ = false;
  bool reset_after_operational_ = false;
  uint32_t timeouts_ = 0;
  uint32_t boot_ups_ = 0;
};

// Sends this node's heartbeat every period on a fixed grid from start(): the
// k-th heartbeat is due at start + k * period. A caller late by more than a
// period gets one heartbeat and the schedule moves to the next grid point
// after now (no burst). A period of 0 disables the producer.
class HeartbeatProducer {
 public:
  HeartbeatProducer(uint8_t node, int64_t period_ns) : node_(node), period_ns_(period_ns) {}

  // Schedules the first heartbeat at `now_ns` (call after the boot-up message).
  void start(int64_t now_ns);
  bool started() const { return started_; }
  bool due(int64_t now_ns) const { return started_ && period_ns_ > 0 && now_ns >= next_ns_; }
  int64_t next_due_ns() const { return next_ns_; }
  // The heartbeat frame with `state` when one is due at now, and the schedule advanced.
  std::optional<CanFrame> poll(int64_t now_ns, NmtState state);
  CanFrame boot_up() const { return encode_heartbeat(node_, NmtState::kBootUp); }

 private:
  uint8_t node_;
  int64_t period_ns_;
  int64_t next_ns_ = 0;
  bool started_ = false;
};

const char* heartbeat_event_name(HeartbeatConsumer::Event e);

}  // namespace rigctl::canopen
