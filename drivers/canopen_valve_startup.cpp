// CanopenValve start-up: open the transport, reset communication, configure
// by SDO, NMT start, wait for operational. Runs on the caller's thread before
// the I/O thread exists, pumping frames itself, so every step is a plain
// sequential wait with one overall deadline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "drivers/canopen/cob_id.hpp"
#include "drivers/canopen_text.hpp"
#include "drivers/canopen_valve.hpp"
#include "drivers/socketcan.hpp"

namespace rigctl {

using namespace canopen;

namespace {

uint32_t whole_ms(double s) { return static_cast<uint32_t>(std::lround(s * 1000.0)); }

std::string seconds(double s) {
  char b[32];
  std::snprintf(b, sizeof b, "%g s", s);
  return b;
}

std::string describe(const SdoWrite& w) {
  return "'" + w.name + "' " + od_address(w.index, w.subindex) + " = " + hex(w.value, 2 * w.size) + " (" +
         std::to_string(w.size) + (w.size == 1 ? " byte)" : " bytes)");
}

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

template <typename Pred>
void CanopenValve::pump_until(Pred done, int64_t deadline_ns, const std::string& what) {
  while (!done()) {
    if (link_lost_) fail("connection lost (" + transport_.name() + ") while waiting for " + what);
    const int64_t now = clock_ns();
    if (now >= deadline_ns) {
      fail("no " + what + " within the start-up timeout of " + seconds(config_.startup_timeout_s));
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

  if (config_.reset_on_start) {
    // Known communication state (pre-operational, PDO and heartbeat objects
    // from the valve's stored values) whatever the previous session left.
    const uint32_t boot_ups = consumer_.boot_ups();
    if (!send(encode_nmt(NmtCommand::kResetCommunication, config_.node_id))) {
      fail("cannot send NMT reset communication: " + std::string(std::strerror(transport_.last_errno())));
    }
    pump_until([&] { return consumer_.boot_ups() > boot_ups; }, deadline_ns,
               "boot-up message after NMT reset communication");
  }

  if (config_.configure_heartbeats) {
    sdo_write({"valve heartbeat producer time (ms)", 0x1017, 0, 2, whole_ms(config_.valve_heartbeat_period_s)},
              deadline_ns);
    sdo_write({"valve heartbeat consumer time of the master", 0x1016, 1, 4,
               consumer_heartbeat_entry(config_.master_node_id,
                                        static_cast<uint16_t>(whole_ms(config_.valve_consumer_time_s)))},
              deadline_ns);
  }
  for (const SdoWrite& w : config_.startup_sdo) sdo_write(w, deadline_ns);

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
}

void CanopenValve::sdo_write(const SdoWrite& w, int64_t deadline_ns) {
  sdo_result_.reset();
  const auto request = sdo_.start_download(w.index, w.subindex, w.value, w.size, clock_ns());
  if (!request) fail("start-up SDO write " + describe(w) + ": SDO client busy");
  if (!send(*request)) {
    sdo_.cancel();
    fail("start-up SDO write " + describe(w) + ": cannot send: " + std::strerror(transport_.last_errno()));
  }
  pump_until([&] { return sdo_result_.has_value(); }, deadline_ns, "SDO response to the start-up write " + describe(w));
  const SdoResult r = *sdo_result_;
  sdo_result_.reset();
  if (r.kind == SdoResult::Kind::kDone) return;

  counters_.sdo_aborts.fetch_add(1, std::memory_order_relaxed);
  std::string msg = "start-up SDO write " + describe(w);
  if (r.kind == SdoResult::Kind::kAbort) {
    msg += " aborted with " + hex(r.abort_code, 8) + ": " + r.text;
    if (r.abort_code == sdo::kAbortTimeout) msg += " (no answer within sdo_timeout_s = " + seconds(config_.sdo_timeout_s) + ")";
  } else {
    msg += " failed: " + std::string(r.text);
  }
  events_.push(prefix() + msg);
  fail(msg);
}

}  // namespace rigctl
