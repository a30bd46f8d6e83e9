#include "drivers/sim/sim_valve_device_state.hpp"

namespace rigctl {

using canopen::cia408::ValveState;

namespace {

// The level the control word's M, H, D bits ask for.
int requested_level(uint16_t cw) {
  if ((cw & canopen::cia408::kBitDisabled) == 0) return 0;
  if ((cw & canopen::cia408::kBitHold) == 0) return 1;
  return (cw & canopen::cia408::kBitActive) ? 3 : 2;
}

int level_of(ValveState s) {
  switch (s) {
    case ValveState::kDisabled: return 1;
    case ValveState::kHold: return 2;
    case ValveState::kActive: return 3;
    default: return 0;
  }
}

constexpr ValveState kLevels[] = {ValveState::kInit, ValveState::kDisabled, ValveState::kHold, ValveState::kActive};

}  // namespace

void SimValveDeviceState::power_on() {
  control_word_ = 0;
  faulted_ = false;
  hold_until_ns_ = 0;
  update();
}

void SimValveDeviceState::update() {
  const int highest = stall_ ? level_of(*stall_) : 3;
  const int wanted = requested_level(control_word_);
  level_ = wanted < highest ? wanted : highest;
}

bool SimValveDeviceState::on_control_word(uint16_t cw) {
  const bool rising_reset = (cw & canopen::cia408::kBitReady) != 0 && (control_word_ & canopen::cia408::kBitReady) == 0;
  control_word_ = cw;
  const bool reset = faulted_ && rising_reset;
  if (reset) faulted_ = false;
  update();
  return reset;
}

void SimValveDeviceState::fault() {
  if (!faulted_) fault_state_ = level_ <= 1 ? ValveState::kFaultDisabled : ValveState::kFaultHold;
  faulted_ = true;
}

ValveState SimValveDeviceState::state() const {
  if (faulted_) return fault_state_;
  if (level_ == 3 && now_ns_ < hold_until_ns_) return ValveState::kHold;
  return kLevels[level_];
}

uint16_t SimValveDeviceState::status_word() const {
  switch (state()) {
    case ValveState::kInit: return 0x0008;
    case ValveState::kDisabled: return 0x0009;
    case ValveState::kHold: return 0x000B;
    case ValveState::kActive: return 0x000F;
    case ValveState::kFaultDisabled: return 0x0001;
    case ValveState::kFaultHold: return 0x0003;
    case ValveState::kFaultReaction: return 0x0007;
    case ValveState::kNotReady:
    case ValveState::kUndefined: return 0x0000;
  }
  return 0x0000;
}

}  // namespace rigctl
