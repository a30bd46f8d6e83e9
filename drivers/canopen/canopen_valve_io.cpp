// CanopenValve frame handling: every received frame is classified, checked
// and either used or counted and dropped (never thrown on); our heartbeat is
// produced and the timeouts are polled. Runs on the start-up thread during
// start(), then on the I/O thread.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <thread>

#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::error_register_text;
using canopen_text::hex;
using canopen_text::milliseconds;
using canopen_text::od_address;

namespace {

std::string frame_text(const CanFrame& f) {
  std::string s = "id " + hex(f.can_id & kCanEffMask, 3) + (f.can_id & kCanRtrFlag ? " RTR" : "") +
                  (f.can_id & kCanEffFlag ? " EFF" : "") + (f.can_id & kCanErrFlag ? " ERR" : "") + " len " +
                  std::to_string(f.len);
  return s;
}

}  // namespace

void CanopenValve::io_loop() {
  while (!stop_requested_.load(std::memory_order_acquire)) {
    if (link_lost_) {
      // Nothing more can arrive; the real-time side already sees kFaultLinkLost.
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    // Wake for our next heartbeat or null setpoint, and at least every 5 ms
    // to poll the consumer timeout and the stop request.
    const int64_t next = std::min(producer_.next_due_ns(), next_keepalive_ns_);
    // Rounded up: rounded down, the last millisecond before a deadline
    // would poll with a zero timeout again and again (a spin at SCHED_FIFO).
    service(static_cast<int>(std::clamp<int64_t>((next - clock_ns() + 999'999) / 1'000'000, 0, 5)));
    repeat_null_setpoint(clock_ns());
  }
}

// While the loop holds the valve safe it writes nothing; the valve's RPDO
// deadline must not expire then. A loop that stalls while driving gets no
// help here: its last setpoint lapses at the deadline, as it should.
void CanopenValve::repeat_null_setpoint(int64_t now_ns) {
  if (now_ns < next_keepalive_ns_) return;
  next_keepalive_ns_ = now_ns + keepalive_ns_;
  if (!running_.load(std::memory_order_acquire) || !safe_hold_.load(std::memory_order_acquire)) return;
  send_rpdo(cia408::kControlActive, 0.0);
  counters_.keepalives.fetch_add(1, std::memory_order_relaxed);
}

void CanopenValve::service(int timeout_ms) {
  CanFrame f;
  const CanTransport::Rx rx = transport_.receive(f, timeout_ms);
  const int64_t now = clock_ns();
  switch (rx) {
    case CanTransport::Rx::kFrame: on_frame(f, now); break;
    case CanTransport::Rx::kBadSize:  // counted by the transport
      if (!bad_size_reported_) {
        bad_size_reported_ = true;
        events_.push(prefix() + "record that is not one CAN frame dropped (further ones are only counted)");
      }
      break;
    case CanTransport::Rx::kHangUp:
    case CanTransport::Rx::kError: on_link_lost(rx); break;
    case CanTransport::Rx::kTimeout: break;
  }
  housekeeping(now);
}

void CanopenValve::housekeeping(int64_t now_ns) {
  if (consumer_.poll(now_ns) == HeartbeatConsumer::Event::kTimedOut) {
    counters_.heartbeat_timeouts.fetch_add(1, std::memory_order_relaxed);
    std::string msg = prefix() + "heartbeat lost: none for " + milliseconds(now_ns - consumer_.last_heartbeat_ns()) +
                      " (timeout " + milliseconds(heartbeat_timeout_ns_) + ")";
    if (expect_operational_) {
      set_fault(kFaultHeartbeatLost);
      msg += "; inputs flagged invalid until restart";
    } else {
      msg += " during start-up";
    }
    events_.push(std::move(msg));
  }
  if (!link_lost_) {
    if (auto hb = producer_.poll(now_ns, NmtState::kOperational)) send(*hb);
  }
  if (sdo_.busy()) {
    SdoResult r = sdo_.poll(now_ns);
    if (r.kind == SdoResult::Kind::kAbort) {
      if (r.to_send) send(*r.to_send);
      sdo_result_ = r;
    }
  }
}

void CanopenValve::on_link_lost(CanTransport::Rx why) {
  if (link_lost_) return;
  link_lost_ = true;
  counters_.link_lost.fetch_add(1, std::memory_order_relaxed);
  set_fault(kFaultLinkLost);
  const std::string reason = why == CanTransport::Rx::kHangUp
                                 ? "peer closed the connection"
                                 : std::string("socket error: ") + std::strerror(transport_.last_errno());
  events_.push(prefix() + "connection lost (" + transport_.name() + "): " + reason +
               "; inputs flagged invalid until restart");
}

void CanopenValve::count_malformed(Malformed m, const CanFrame& f) {
  const auto i = static_cast<std::size_t>(m);
  if (i == 0 || i >= kMalformedReasons) return;
  counters_.malformed[i].fetch_add(1, std::memory_order_relaxed);
  if (!malformed_reported_[i]) {
    malformed_reported_[i] = true;
    events_.push(prefix() + "malformed frame dropped (" + malformed_text(m) + "): " + frame_text(f) +
                 "; further ones are only counted");
  }
}

void CanopenValve::on_frame(const CanFrame& f, int64_t now_ns) {
  CobInfo info;
  if (const Malformed m = check_frame(f, info); m != Malformed::kNone) {
    count_malformed(m, f);
    return;
  }
  if (info.node != config_.node_id) {  // another node, or NMT/SYNC/TIME (node 0): not ours to use
    counters_.ignored.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (f.id() == actual_cob_) {
    on_actual(f, now_ns);
    return;
  }
  switch (info.function) {
    case Function::kHeartbeat: {
      Heartbeat hb;
      if (const Malformed m = decode_heartbeat(f, hb); m != Malformed::kNone) {
        count_malformed(m, f);
        return;
      }
      counters_.accepted.fetch_add(1, std::memory_order_relaxed);
      on_heartbeat(hb, now_ns);
      return;
    }
    case Function::kEmcy: {
      Emcy e;
      if (const Malformed m = decode_emcy(f, e); m != Malformed::kNone) {
        count_malformed(m, f);
        return;
      }
      counters_.accepted.fetch_add(1, std::memory_order_relaxed);
      on_emcy(e);
      return;
    }
    case Function::kSdoTx: on_sdo(f, now_ns); return;
    default: counters_.ignored.fetch_add(1, std::memory_order_relaxed); return;  // e.g. an unmapped TPDO
  }
}

void CanopenValve::on_actual(const CanFrame& f, int64_t now_ns) {
  std::array<double, PdoMapping::kMaxEntries> v{};
  if (const Malformed m = decode_pdo(tpdo_map_, f, v); m != Malformed::kNone) {
    count_malformed(m, f);
    return;
  }
  counters_.accepted.fetch_add(1, std::memory_order_relaxed);
  counters_.actual.fetch_add(1, std::memory_order_relaxed);
  ValveActual a;
  a.rx_ns = now_ns;
  a.count = ++actual_count_;
  a.status_word = static_cast<uint16_t>(v[0]);
  a.spool = v[1];
  a.pressure = tpdo_map_.size() > 2 ? v[2] : 0.0;
  latest_.store(a);

  on_device_state(a.status_word);
}

// Any departure from DEVICE MODE ACTIVE once running is latched: the valve
// stopped following the setpoint, and one that comes back must not take up
// whatever the loop would have sent meanwhile.
void CanopenValve::on_device_state(uint16_t status_word) {
  const auto state = cia408::valve_state(status_word);
  const bool changed = actual_count_ == 1 || state != cia408::valve_state(last_status_word_);
  last_status_word_ = status_word;
  if (!changed) return;
  std::string msg = prefix() + "valve device state " + cia408::valve_state_name(state) + " (status word " +
                    hex(status_word, 4) + ")";
  if (expect_operational_ && state != cia408::ValveState::kActive && (faults() & kFaultDeviceState) == 0) {
    left_active_status_word_.store(status_word, std::memory_order_release);
    set_fault(kFaultDeviceState);
    counters_.left_active.fetch_add(1, std::memory_order_relaxed);
    msg += ": left DEVICE MODE ACTIVE, inputs flagged invalid until restart";
  }
  events_.push(std::move(msg));
}

void CanopenValve::on_heartbeat(const Heartbeat& hb, int64_t now_ns) {
  last_heartbeat_ns_.store(now_ns, std::memory_order_release);
  valve_state_.store(static_cast<uint8_t>(hb.state), std::memory_order_release);
  using E = HeartbeatConsumer::Event;
  const char* const state = nmt_state_name(hb.state);  // strings are built only for an event
  switch (consumer_.on_heartbeat(hb, now_ns)) {
    case E::kResetAfterOperational:
      counters_.valve_resets.fetch_add(1, std::memory_order_relaxed);
      if (expect_operational_) {
        set_fault(kFaultValveReset);
        events_.push(prefix() + "valve reset: boot-up message while operational; inputs flagged invalid until restart");
      } else {
        consumer_.clear_reset();  // the reset we asked for at start-up
        events_.push(prefix() + "boot-up (was operational before this start-up)");
      }
      break;
    case E::kRecovered:
      events_.push(prefix() + "heartbeat back, NMT state " + state +
                   (expect_operational_ ? " (still flagged invalid until restart)" : ""));
      break;
    case E::kStateChanged: events_.push(prefix() + "valve NMT state now " + state); break;
    case E::kBootUp: events_.push(prefix() + "boot-up"); break;
    case E::kFirstSeen: events_.push(prefix() + "first heartbeat, NMT state " + state); break;
    default: break;
  }
  if (expect_operational_) {
    if (hb.state == NmtState::kOperational) {
      clear_fault(kFaultNotOperational);
    } else {
      set_fault(kFaultNotOperational);
    }
  }
}

void CanopenValve::on_emcy(const Emcy& e) {
  counters_.emcy.fetch_add(1, std::memory_order_relaxed);
  // The error register is the valve's own summary of what is active now: any
  // bit set means the valve is in error, 0 means it has recovered.
  const bool active = e.error_register != 0;
  if (active) {
    last_emcy_code_.store(e.error_code, std::memory_order_release);
    last_emcy_register_.store(e.error_register, std::memory_order_release);
    set_fault(kFaultEmcy);
  } else {
    clear_fault(kFaultEmcy);
  }
  std::string data;
  for (uint8_t b : e.manufacturer) data += " " + hex(b, 2).substr(2);
  events_.push(prefix() + "EMCY " + hex(e.error_code, 4) + " (" + emcy_code_text(e.error_code) + "), error register " +
               hex(e.error_register, 2) + " (" + error_register_text(e.error_register) + "), manufacturer data" + data +
               (active ? ": inputs flagged invalid until the error register clears" : ": no error active"));
}

void CanopenValve::on_sdo(const CanFrame& f, int64_t now_ns) {
  SdoResult r = sdo_.on_frame(f, now_ns);
  switch (r.kind) {
    case SdoResult::Kind::kMalformed: count_malformed(r.malformed, f); return;
    case SdoResult::Kind::kIgnored: counters_.ignored.fetch_add(1, std::memory_order_relaxed); return;
    case SdoResult::Kind::kPending:  // a segment of a segmented upload: ask for the next
      counters_.accepted.fetch_add(1, std::memory_order_relaxed);
      if (r.to_send) send(*r.to_send);
      return;
    default:
      counters_.accepted.fetch_add(1, std::memory_order_relaxed);
      if (r.to_send) send(*r.to_send);
      sdo_result_ = r;
      return;
  }
}

}  // namespace rigctl
