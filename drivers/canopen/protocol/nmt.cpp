#include "drivers/canopen/protocol/nmt.hpp"

#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl::canopen {

namespace {

bool defined_state(uint8_t s) {
  return s == 0x00 || s == 0x04 || s == 0x05 || s == 0x7F;
}

bool defined_command(uint8_t c) {
  return c == 0x01 || c == 0x02 || c == 0x80 || c == 0x81 || c == 0x82;
}

// now - then for now >= then, without signed overflow; 0 if time went backwards.
uint64_t elapsed(int64_t then, int64_t now) {
  return now > then ? static_cast<uint64_t>(now) - static_cast<uint64_t>(then) : 0;
}

}  // namespace

const char* nmt_state_name(NmtState s) {
  switch (s) {
    case NmtState::kBootUp: return "boot-up";
    case NmtState::kStopped: return "stopped";
    case NmtState::kOperational: return "operational";
    case NmtState::kPreOperational: return "pre-operational";
  }
  return "?";
}

const char* nmt_command_name(NmtCommand c) {
  switch (c) {
    case NmtCommand::kStart: return "start";
    case NmtCommand::kStop: return "stop";
    case NmtCommand::kEnterPreOperational: return "enter pre-operational";
    case NmtCommand::kResetNode: return "reset node";
    case NmtCommand::kResetCommunication: return "reset communication";
  }
  return "?";
}

CanFrame encode_nmt(NmtCommand command, uint8_t node) {
  return make_frame(kCobNmt, {static_cast<uint8_t>(command), node});
}

Malformed decode_nmt(const CanFrame& frame, NmtMessage& out) {
  CobInfo info;
  if (const Malformed m = check_frame_for(frame, Function::kNmt, info); m != Malformed::kNone) return m;
  if (!defined_command(frame.data[0]) || frame.data[1] > kMaxNodeId) return Malformed::kBadContent;
  out.command = static_cast<NmtCommand>(frame.data[0]);
  out.node = frame.data[1];
  return Malformed::kNone;
}

CanFrame encode_heartbeat(uint8_t node, NmtState state) {
  return make_frame(kCobHeartbeatBase + (node & 0x7F), {static_cast<uint8_t>(state)});
}

Malformed decode_heartbeat(const CanFrame& frame, Heartbeat& out) {
  CobInfo info;
  if (const Malformed m = check_frame_for(frame, Function::kHeartbeat, info); m != Malformed::kNone) return m;
  const uint8_t state = frame.data[0] & 0x7F;  // bit 7: node-guarding toggle, reserved here
  if (!defined_state(state)) return Malformed::kBadContent;
  out.node = info.node;
  out.state = static_cast<NmtState>(state);
  return Malformed::kNone;
}

HeartbeatConsumer::Event HeartbeatConsumer::on_heartbeat(const Heartbeat& hb, int64_t now_ns) {
  if (hb.node != node_) return Event::kNone;
  const Status before = status_;
  const NmtState previous = last_state_;
  status_ = Status::kAlive;
  last_ns_ = now_ns;
  last_state_ = hb.state;

  if (hb.state == NmtState::kBootUp) {
    ++boot_ups_;
    const bool was_operational = operational_since_boot_;
    operational_since_boot_ = false;
    if (was_operational) {
      reset_after_operational_ = true;
      return Event::kResetAfterOperational;
    }
    return before == Status::kNeverSeen ? Event::kFirstSeen : Event::kBootUp;
  }
  if (hb.state == NmtState::kOperational) operational_since_boot_ = true;
  if (before == Status::kNeverSeen) return Event::kFirstSeen;
  if (before == Status::kTimedOut) return Event::kRecovered;
  return previous != hb.state ? Event::kStateChanged : Event::kNone;
}

HeartbeatConsumer::Event HeartbeatConsumer::poll(int64_t now_ns) {
  if (status_ != Status::kAlive || consumer_time_ns_ <= 0) return Event::kNone;
  if (elapsed(last_ns_, now_ns) <= static_cast<uint64_t>(consumer_time_ns_)) return Event::kNone;
  status_ = Status::kTimedOut;
  ++timeouts_;
  return Event::kTimedOut;
}

void HeartbeatConsumer::reset() {
  status_ = Status::kNeverSeen;
  last_state_ = NmtState::kBootUp;
  last_ns_ = 0;
  operational_since_boot_ = false;
  reset_after_operational_ = false;
}

void HeartbeatProducer::start(int64_t now_ns) {
  started_ = true;
  next_ns_ = now_ns;
}

std::optional<CanFrame> HeartbeatProducer::poll(int64_t now_ns, NmtState state) {
  if (!due(now_ns)) return std::nullopt;
  const auto period = static_cast<uint64_t>(period_ns_);
  // Next grid point strictly after now: next + k*period with k >= 1.
  const uint64_t late = elapsed(next_ns_, now_ns);
  const uint64_t steps = late / period + 1;
  next_ns_ = static_cast<int64_t>(static_cast<uint64_t>(next_ns_) + steps * period);
  return encode_heartbeat(node_, state);
}

const char* heartbeat_event_name(HeartbeatConsumer::Event e) {
  using E = HeartbeatConsumer::Event;
  switch (e) {
    case E::kNone: return "none";
    case E::kFirstSeen: return "first heartbeat";
    case E::kStateChanged: return "state changed";
    case E::kRecovered: return "heartbeat recovered";
    case E::kTimedOut: return "heartbeat timed out";
    case E::kBootUp: return "boot-up";
    case E::kResetAfterOperational: return "boot-up after operational (node reset)";
  }
  return "?";
}

}  // namespace rigctl::canopen
