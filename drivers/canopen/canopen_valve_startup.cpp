// CanopenValve start-up: open the transport, reset communication, configure
// by SDO, NMT start, wait for operational, walk the device state machine to
// DEVICE MODE ACTIVE. Runs on the caller's thread before the I/O thread
// exists, pumping frames itself, so every step is a plain sequential wait
// with one overall deadline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/socketcan.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::hex;
using canopen_text::milliseconds;
using canopen_text::seconds;

namespace {
uint32_t whole_ms(double s) { return static_cast<uint32_t>(std::lround(s * 1000.0)); }
int64_t to_ns(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }
}  // namespace

void CanopenValve::fail(const std::string& what) const { throw std::runtime_error(prefix() + what); }

CanTransport CanopenValve::open_transport(int64_t deadline_ns) {
  if (!config_.interface.empty()) {
    // The kernel filters to this node's frames; a real bus carries others.
    const uint32_t ids[] = {actual_cob_, cob_id(Function::kEmcy, config_.node_id),
                            cob_id(Function::kSdoTx, config_.node_id), cob_id(Function::kHeartbeat, config_.node_id)};
    try {
      return open_socketcan(config_.interface, ids);
    } catch (const std::exception& e) {
      fail(e.what());
    }
  }
  if (config_.socket_path.empty()) fail("no transport configured: give interface or socket_path");
  // The simulated valve may still be starting: retry until the deadline.
  for (;;) {
    try {
      return connect_seqpacket(config_.socket_path);
    } catch (const std::exception& e) {
      if (clock_ns() >= deadline_ns) {
        fail(std::string(e.what()) + " (gave up after the start-up timeout of " + seconds(config_.startup_timeout_s) + ")");
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void CanopenValve::pump_until(const std::function<bool()>& done, int64_t deadline_ns, const std::string& what,
                              const std::string& limit) {
  while (!done()) {
    if (link_lost_) fail("connection lost (" + transport_.name() + ") while waiting for " + what);
    const int64_t now = clock_ns();
    if (now >= deadline_ns) {
      fail("no " + what + " within " +
           (limit.empty() ? "the start-up timeout of " + seconds(config_.startup_timeout_s) : limit));
    }
    const int64_t left_ms = (deadline_ns - now) / 1'000'000 + 1;
    service(static_cast<int>(std::clamp<int64_t>(left_ms, 1, 5)));
  }
}

void CanopenValve::run_startup(int64_t deadline_ns) {
  // We are a node too: our heartbeat runs from the first moment, so a valve
  // whose consumer is already configured never sees us missing.
  producer_.start(clock_ns());
  housekeeping(clock_ns());

  if (config_.reset_on_start) reset_communication(deadline_ns);
  read_identity(deadline_ns);
  if (config_.configure_heartbeats) {
    sdo_write({"valve heartbeat producer time (ms)", 0x1017, 0, 2, whole_ms(config_.valve_heartbeat_period_s)},
              deadline_ns);
    sdo_write({"valve heartbeat consumer time of the master", 0x1016, 1, 4,
               consumer_heartbeat_entry(config_.master_node_id,
                                        static_cast<uint16_t>(whole_ms(config_.valve_consumer_time_s)))},
              deadline_ns);
  }
  configure_pdos(deadline_ns);
  read_spool_scale(deadline_ns);
  for (const SdoWrite& w : config_.startup_sdo) sdo_write(w, deadline_ns);
  start_operational(deadline_ns);
  walk_to_active(deadline_ns);
}

// Known communication state (pre-operational, PDO and heartbeat objects
// from the valve's stored values) whatever the previous session left. What
// arrived before the reset cannot answer it: a boot-up already queued (the
// valve's power-on, or one from before we connected) is discarded, and only
// a boot-up received after the reset went out counts.
void CanopenValve::reset_communication(int64_t deadline_ns) {
  uint64_t discarded = 0;
  CanFrame stale;
  for (CanTransport::Rx rx; (rx = transport_.receive(stale, 0)) != CanTransport::Rx::kTimeout;) {
    if (rx == CanTransport::Rx::kHangUp || rx == CanTransport::Rx::kError) {
      on_link_lost(rx);
      break;
    }
    ++discarded;
  }
  counters_.discarded_before_reset.fetch_add(discarded, std::memory_order_relaxed);
  const uint32_t boot_ups = consumer_.boot_ups();
  const int64_t sent_ns = clock_ns();
  if (!send(encode_nmt(NmtCommand::kResetCommunication, config_.node_id))) {
    fail("cannot send NMT reset communication: " + std::string(std::strerror(transport_.last_errno())));
  }
  pump_until([&] { return consumer_.boot_ups() > boot_ups; }, std::min(deadline_ns, sent_ns + to_ns(config_.boot_timeout_s)),
             "boot-up message after NMT reset communication",
             "boot_timeout_s = " + seconds(config_.boot_timeout_s));
  events_.push(prefix() + "boot-up " + milliseconds(consumer_.last_heartbeat_ns() - sent_ns) +
               " after NMT reset communication (" + std::to_string(discarded) + " frame(s) queued before it discarded)");
}

void CanopenValve::start_operational(int64_t deadline_ns) {
  if (!send(encode_nmt(NmtCommand::kStart, config_.node_id))) {
    fail("cannot send NMT start: " + std::string(std::strerror(transport_.last_errno())));
  }
  try {
    pump_until([&] { return consumer_.alive() && consumer_.last_state() == NmtState::kOperational; }, deadline_ns,
               "heartbeat reporting NMT operational after NMT start");
  } catch (const std::runtime_error& e) {
    if (link_lost_) throw;
    std::string seen = consumer_.status() == HeartbeatConsumer::Status::kNeverSeen
                           ? "no heartbeat received at all: is the valve's heartbeat producer time 0x1017 set?"
                           : std::string("last heartbeat reported ") + nmt_state_name(consumer_.last_state());
    throw std::runtime_error(std::string(e.what()) + " (" + seen + ")");
  }
  // Ready means usable: the loop's first read must not find "never received".
  pump_until([&] { return actual_count_ > 0; }, deadline_ns,
             "spool actual value (TPDO" + std::to_string(config_.actual_tpdo) + ", COB-ID " + hex(actual_cob_, 3) +
                 ") after NMT start; check the valve's TPDO transmission type and event timer (" +
                 hex(static_cast<uint32_t>(0x1800 + config_.actual_tpdo - 1), 4) + " sub 2 and 5)");
}

}  // namespace rigctl
