// CanopenValve start-up: the CiA 408 device state machine walked to DEVICE
// MODE ACTIVE by the RPDO's control word, with the null setpoint, one state
// at a time (INIT -> DISABLED -> HOLD -> ACTIVE; a fault state gets a fault
// reset). Each step must be taken within device_state_timeout_s; a valve
// that stays short of ACTIVE (an enable input not wired, a fault that does
// not clear) is refused before the loop can drive it.
#include <algorithm>

#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/canopen/protocol/cia408.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::hex;
using canopen_text::seconds;

namespace {
int64_t to_ns(double s) { return static_cast<int64_t>(s * 1e9 + 0.5); }
constexpr int64_t kResendNs = 5'000'000;  // the control word again every 5 ms: a lost RPDO costs little
}  // namespace

void CanopenValve::walk_to_active(int64_t deadline_ns) {
  using cia408::ValveState;
  ValveState state = cia408::valve_state(last_status_word_);
  uint16_t control_word = 0xFFFF;
  int64_t step_started = clock_ns();
  const int64_t resend_ns = std::min(kResendNs, keepalive_ns_);
  while (state != ValveState::kActive) {
    uint16_t wanted = cia408::control_word_toward_active(state);
    // A fault reset is a rising edge of bit 3: after one, the next word drops it.
    if ((wanted & cia408::kBitReady) && control_word != 0xFFFF && (control_word & cia408::kBitReady)) {
      wanted = static_cast<uint16_t>(wanted & ~cia408::kBitReady);
    }
    if ((wanted & ~cia408::kBitReady) != (control_word & ~cia408::kBitReady)) {
      step_started = clock_ns();
      events_.push(prefix() + "device state " + cia408::valve_state_name(state) + " (status word " +
                   hex(last_status_word_, 4) + "): control word " + hex(wanted, 4));
    }
    control_word = wanted;
    send_rpdo(control_word, 0.0);
    const ValveState before = state;
    const int64_t resend_at = clock_ns() + resend_ns;
    pump_until([&] { return cia408::valve_state(last_status_word_) != before || clock_ns() >= resend_at; }, deadline_ns,
               "DEVICE MODE ACTIVE (device state " + std::string(cia408::valve_state_name(before)) + ")");
    state = cia408::valve_state(last_status_word_);
    if (state == before && clock_ns() - step_started > to_ns(config_.device_state_timeout_s)) {
      fail("the valve does not reach DEVICE MODE ACTIVE: it stays in device state " +
           std::string(cia408::valve_state_name(state)) + " (status word " + hex(last_status_word_, 4) +
           ") with control word " + hex(control_word, 4) + " for device_state_timeout_s = " +
           seconds(config_.device_state_timeout_s) +
           " (check its enable input, device mode 0x6042 and its faults); refused before the loop drives it");
    }
  }
  events_.push(prefix() + "device state DEVICE_MODE_ACTIVE (status word " + hex(last_status_word_, 4) + ")");
}

}  // namespace rigctl
