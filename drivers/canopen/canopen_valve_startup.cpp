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

#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/canopen/socketcan.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::hex;
using canopen_text::milliseconds;
using canopen_text::od_address;

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

  read_identity(deadline_ns);
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
  // Ready means usable: the loop's first read must not find "never received".
  pump_until([&] { return actual_count_ > 0; }, deadline_ns,
             "spool actual value (TPDO" + std::to_string(config_.actual_tpdo) + ", COB-ID " + hex(actual_cob_, 3) +
                 ") after NMT start; check the valve's TPDO transmission type and event timer (" +
                 hex(static_cast<uint32_t>(0x1800 + config_.actual_tpdo - 1), 4) + " sub 2 and 5)");
}

canopen::SdoResult CanopenValve::sdo_transfer(const std::optional<CanFrame>& request, const std::string& what,
                                              int64_t deadline_ns) {
  sdo_result_.reset();
  if (!request) fail(what + ": SDO client busy");
  if (!send(*request)) {
    sdo_.cancel();
    fail(what + ": cannot send: " + std::strerror(transport_.last_errno()));
  }
  pump_until([&] { return sdo_result_.has_value(); }, deadline_ns, "SDO response to the " + what);
  const SdoResult r = *sdo_result_;
  sdo_result_.reset();
  if (r.kind != SdoResult::Kind::kDone) counters_.sdo_aborts.fetch_add(1, std::memory_order_relaxed);
  return r;
}

namespace {
std::string failure_text(const SdoResult& r, double sdo_timeout_s) {
  if (r.kind != SdoResult::Kind::kAbort) return " failed: " + std::string(r.text);
  std::string msg = " aborted with " + hex(r.abort_code, 8) + ": " + r.text;
  if (r.abort_code == sdo::kAbortTimeout) msg += " (no answer within sdo_timeout_s = " + seconds(sdo_timeout_s) + ")";
  return msg;
}
}  // namespace

void CanopenValve::sdo_write(const SdoWrite& w, int64_t deadline_ns) {
  const std::string what = "start-up SDO write " + describe(w);
  const SdoResult r = sdo_transfer(sdo_.start_download(w.index, w.subindex, w.value, w.size, clock_ns()), what, deadline_ns);
  if (r.kind == SdoResult::Kind::kDone) return;
  const std::string msg = what + failure_text(r, config_.sdo_timeout_s);
  events_.push(prefix() + msg);
  fail(msg);
}

std::optional<uint32_t> CanopenValve::sdo_read(uint16_t index, uint8_t subindex, const std::string& what, bool required,
                                               int64_t deadline_ns) {
  const std::string full = "start-up SDO read of the " + what + " " + od_address(index, subindex);
  const SdoResult r = sdo_transfer(sdo_.start_upload(index, subindex, clock_ns()), full, deadline_ns);
  if (r.kind == SdoResult::Kind::kDone) return r.value;
  const std::string msg = full + failure_text(r, config_.sdo_timeout_s);
  events_.push(prefix() + msg + (required ? "" : " (optional object: ignored)"));
  if (required) fail(msg);
  return std::nullopt;
}

void CanopenValve::read_identity(int64_t deadline_ns) {
  ValveIdentity id;
  id.device_type = *sdo_read(0x1000, 0, "device type", true, deadline_ns);
  id.vendor_id = *sdo_read(0x1018, 1, "vendor id", true, deadline_ns);
  id.product_code = sdo_read(0x1018, 2, "product code", false, deadline_ns);
  id.revision = sdo_read(0x1018, 3, "revision number", false, deadline_ns);
  id.serial = sdo_read(0x1018, 4, "serial number", false, deadline_ns);
  auto opt = [](const std::optional<uint32_t>& v) { return v ? hex(*v, 8) : std::string("n/a"); };
  events_.push(prefix() + "identity: device type " + hex(id.device_type, 8) + ", vendor " + hex(id.vendor_id, 8) +
               ", product " + opt(id.product_code) + ", revision " + opt(id.revision) + ", serial " + opt(id.serial));
  // Not fatal: some valves report a manufacturer-specific device type.
  if ((id.device_type & 0xFFFF) != 408) {
    events_.push(prefix() + "warning: device type " + hex(id.device_type, 8) + " does not name the CiA 408 profile");
  }
  std::lock_guard<std::mutex> lock(admin_mutex_);
  identity_ = id;
}

}  // namespace rigctl
