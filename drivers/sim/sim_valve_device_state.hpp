// The CiA 408 device state machine of the simulated valve node
// (drivers/canopen/protocol/cia408.hpp has the states and bits). Every
// transition between the present state and the one the control word asks
// for is taken at once, up to an optional stall state (a valve whose enable
// input is missing stays DISABLED whatever it is told); a fault takes it to
// FAULT_HOLD (FAULT_DISABLED from INIT or DISABLED) until a rising edge of
// control word bit 3; an injected internal event can hold it in HOLD for a
// while, after which it returns to what the control word asks for. Plain
// state, owned by the node's thread.
#pragma once

#include <cstdint>
#include <optional>

#include "drivers/canopen/protocol/cia408.hpp"

namespace rigctl {

class SimValveDeviceState {
 public:
  using State = canopen::cia408::ValveState;

  // Power on or reset node: INIT, no fault, control word 0.
  void power_on();
  // A new control word. True when it reset a fault (a rising edge of bit 3
  // while in a fault state).
  bool on_control_word(uint16_t control_word);
  // A fault (e.g. the master's heartbeat lost): to FAULT_HOLD or FAULT_DISABLED.
  void fault();
  // An NMT reset: the fault is gone, the control word decides again.
  void clear_fault() { faulted_ = false; }
  // The highest state the valve reaches (nullopt: DEVICE MODE ACTIVE).
  void set_stall(std::optional<State> highest) { stall_ = highest; update(); }
  // From now_ns until until_ns an ACTIVE valve is in HOLD.
  void force_hold(int64_t until_ns) { hold_until_ns_ = until_ns; }
  void step(int64_t now_ns) { now_ns_ = now_ns; }

  State state() const;
  uint16_t status_word() const;
  bool faulted() const { return faulted_; }
  bool active() const { return state() == State::kActive; }
  bool holding() const { return state() == State::kHold || state() == State::kFaultHold; }
  uint16_t control_word() const { return control_word_; }

 private:
  void update();

  uint16_t control_word_ = 0;
  int level_ = 0;  // 0 INIT, 1 DISABLED, 2 HOLD, 3 ACTIVE: what the control word got
  std::optional<State> stall_;
  bool faulted_ = false;
  State fault_state_ = State::kFaultHold;
  int64_t hold_until_ns_ = 0;
  int64_t now_ns_ = 0;
};

}  // namespace rigctl
