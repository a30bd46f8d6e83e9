// CanopenValve start-up by SDO: one transfer at a time (a request that times
// out is sent once more), the writes and reads of the start-up, the valve's
// identity and its spool scale.
#include <cstring>
#include <stdexcept>

#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/canopen/protocol/cia408.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::hex;
using canopen_text::od_address;
using canopen_text::seconds;

namespace {

std::string describe(const SdoWrite& w) {
  return "'" + w.name + "' " + od_address(w.index, w.subindex) + " = " + hex(w.value, 2 * w.size) + " (" +
         std::to_string(w.size) + (w.size == 1 ? " byte)" : " bytes)");
}

std::string failure_text(const SdoResult& r, double sdo_timeout_s) {
  if (r.kind != SdoResult::Kind::kAbort) {
    return " failed: " + std::string(r.text) + (r.abort_code != 0 ? " (we aborted it with " + hex(r.abort_code, 8) + ")" : "");
  }
  std::string msg = " aborted with " + hex(r.abort_code, 8) + ": " + r.text;
  if (r.abort_code == sdo::kAbortTimeout) msg += " (no answer within sdo_timeout_s = " + seconds(sdo_timeout_s) + ", twice)";
  return msg;
}

// Our own timeout (we send the abort): the request or its answer may have
// been lost, or the valve was busy; worth one more try.
bool timed_out_here(const SdoResult& r) {
  return r.kind == SdoResult::Kind::kAbort && r.abort_code == sdo::kAbortTimeout && r.to_send.has_value();
}

}  // namespace

SdoResult CanopenValve::sdo_transfer(const std::function<std::optional<CanFrame>()>& start, const std::string& what,
                                     int64_t deadline_ns) {
  for (int attempt = 1;; ++attempt) {
    sdo_result_.reset();
    const std::optional<CanFrame> request = start();
    if (!request) fail(what + ": SDO client busy");
    if (!send(*request)) {
      sdo_.cancel();
      fail(what + ": cannot send: " + std::strerror(transport_.last_errno()));
    }
    pump_until([&] { return sdo_result_.has_value(); }, deadline_ns, "SDO response to the " + what);
    const SdoResult r = *sdo_result_;
    sdo_result_.reset();
    if (attempt == 1 && timed_out_here(r)) {
      counters_.sdo_retries.fetch_add(1, std::memory_order_relaxed);
      events_.push(prefix() + what + ": no answer within sdo_timeout_s = " + seconds(config_.sdo_timeout_s) +
                   ", sent once more");
      continue;
    }
    if (r.kind != SdoResult::Kind::kDone) counters_.sdo_aborts.fetch_add(1, std::memory_order_relaxed);
    return r;
  }
}

void CanopenValve::sdo_write(const SdoWrite& w, int64_t deadline_ns) {
  const std::string what = "start-up SDO write " + describe(w);
  const SdoResult r = sdo_transfer([&] { return sdo_.start_download(w.index, w.subindex, w.value, w.size, clock_ns()); },
                                   what, deadline_ns);
  if (r.kind == SdoResult::Kind::kDone) return;
  const std::string msg = what + failure_text(r, config_.sdo_timeout_s);
  events_.push(prefix() + msg);
  fail(msg);
}

std::optional<uint32_t> CanopenValve::sdo_read(uint16_t index, uint8_t subindex, const std::string& what, bool required,
                                               int64_t deadline_ns) {
  const std::string full = "start-up SDO read of the " + what + " " + od_address(index, subindex);
  const SdoResult r = sdo_transfer([&] { return sdo_.start_upload(index, subindex, clock_ns()); }, full, deadline_ns);
  std::string msg;
  if (r.kind != SdoResult::Kind::kDone) {
    msg = full + failure_text(r, config_.sdo_timeout_s);
  } else if (r.size > 4) {
    msg = full + " failed: " + std::to_string(r.size) + " bytes came, a number of at most 4 was expected";
  } else {
    return r.value;
  }
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
  {
    std::lock_guard<std::mutex> lock(admin_mutex_);
    identity_ = id;
  }
  // Another profile's device does something else with our PDOs: an I/O
  // module (CiA 401) would take the setpoint as its outputs.
  const uint16_t profile = cia408::device_profile(id.device_type);
  if (profile != cia408::kProfileNumber) {
    fail("device type " + hex(id.device_type, 8) + " (0x1000) names device profile CiA " + std::to_string(profile) +
         ", not CiA 408 (proportional valves): refused, this client drives only CiA 408 valves");
  }
}

// The counts that mean 100 % spool: the valve's reference value 0x6311:1
// where it has one (a configured value must agree with it), else the
// configured one; with neither the setpoint's scale is unknown.
void CanopenValve::read_spool_scale(int64_t deadline_ns) {
  const auto ref = sdo_read(cia408::kSplReferenceValue, cia408::kValueSubindex, "spool reference value (counts for 100 %)",
                            false, deadline_ns);
  const int configured = config_.spool_full_scale;
  int full = configured;
  if (ref) {
    const int32_t valve = sdo_sign_extend(*ref, 2);
    if (valve <= 0) fail("the valve's spool reference value 0x6311:01 is " + std::to_string(valve) + ": not a scale");
    if (configured > 0 && configured != valve) {
      fail("canopen.spool_full_scale is " + std::to_string(configured) + " but the valve's reference value 0x6311:01 is " +
           std::to_string(valve) + ": the setpoint would be scaled wrongly");
    }
    full = valve;
  } else if (configured == 0) {
    fail("the valve has no spool reference value 0x6311:01 and canopen.spool_full_scale is not set: the setpoint's "
         "scale is unknown");
  }
  set_spool_scale(full);
  events_.push(prefix() + "spool scale: " + std::to_string(full) + " counts = 100 % (" +
               (ref ? "the valve's 0x6311:01" : "canopen.spool_full_scale; the valve has no 0x6311:01") + ")");
}

}  // namespace rigctl
