// CanopenValve::flag_cause: the first reason the inputs were flagged in a
// session, in words, for the console's fault line and the logs.
#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/canopen/protocol/cia408.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::error_register_text;
using canopen_text::hex;
using canopen_text::milliseconds;

namespace {
int64_t to_ns(double s) { return static_cast<int64_t>(s * 1e9 + 0.5); }
}  // namespace

std::string CanopenValve::flag_cause() const {
  const auto why = first_flag_reason();
  const uint16_t sw = first_flag_status_word_.load(std::memory_order_acquire);
  const int64_t age = first_flag_age_ns_.load(std::memory_order_acquire);
  const std::string aged = age >= 0 ? milliseconds(age) : std::string("never");
  std::string text;
  switch (why) {
    case FlagReason::kNone: return "";
    case FlagReason::kLinkLost: text = "connection to the valve lost"; break;
    case FlagReason::kValveReset: text = "valve reset (boot-up message while operational)"; break;
    case FlagReason::kHeartbeatLost:
      text = "heartbeat lost (none within heartbeat_timeout_s = " + milliseconds(heartbeat_timeout_ns_) + ")";
      break;
    case FlagReason::kHeartbeatStale:
      text = "heartbeat lost (last one " + aged + " before, heartbeat_timeout_s = " + milliseconds(heartbeat_timeout_ns_) + ")";
      break;
    case FlagReason::kEmcy: {
      const uint16_t code = last_emcy_code_.load(std::memory_order_acquire);
      const uint8_t reg = last_emcy_register_.load(std::memory_order_acquire);
      text = "EMCY " + hex(code, 4) + " (" + emcy_code_text(code) + "), error register " + hex(reg, 2) + " (" +
             error_register_text(reg) + ")";
      break;
    }
    case FlagReason::kNotOperational:
      text = std::string("NMT state ") + nmt_state_name(static_cast<NmtState>(first_flag_nmt_.load(std::memory_order_acquire))) +
             " (heartbeat), not operational";
      break;
    case FlagReason::kDeviceState:
      text = std::string("left DEVICE MODE ACTIVE: device state ") + cia408::valve_state_name(cia408::valve_state(sw)) +
             " (status word " + hex(sw, 4) + ")";
      break;
    case FlagReason::kNoActualValue: text = "no spool actual value received"; break;
    case FlagReason::kActualStale:
      text = "spool actual value " + aged + " old (actual_max_age_s = " + milliseconds(to_ns(config_.actual_max_age_s)) + ")";
      break;
  }
  return prefix() + text;
}

}  // namespace rigctl
