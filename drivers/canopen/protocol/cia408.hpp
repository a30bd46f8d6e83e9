// CiA 408 (device profile fluid power technology: proportional valves and
// hydrostatic transmissions) objects a Moog-style servovalve uses, with the
// profile's default p/Q PDO mapping (RPDO: control word, spool setpoint,
// pressure setpoint; TPDO: status word, spool actual value, pressure actual
// value). Spool setpoint/actual value are INTEGER16; the count that means
// 100 % is the valve's reference value 0x6311:1 (16384 on the valves the
// project knows; the client reads it). Pressure scaling depends on the
// valve's pressure reference, so it is a parameter.
//
// The device state machine (DSM): the control word's bits M, H, D (2..0)
// ask for a state, the status word's bits R, M, H, D (3..0) report it:
//   NOT_READY 0000 -> INIT 1000 (automatic) -> DISABLED 1001 (control xx1)
//   -> HOLD 1011 (x11) -> DEVICE MODE ACTIVE 1111 (111), and back down as
//   the bits clear. Only in ACTIVE does the valve follow the bus setpoint:
//   HOLD controls to the hold setpoint 0x6314, DISABLED and INIT leave the
//   spool at its hydraulic fail-safe position. A fault takes it to
//   FAULT_REACTION 0111 and then FAULT_HOLD 0011 or FAULT_DISABLED 0001
//   (ready bit clear); a rising edge of control word bit 3 resets the fault.
#pragma once

#include <cstdint>

#include "drivers/canopen/protocol/pdo.hpp"

namespace rigctl::canopen::cia408 {

inline constexpr uint16_t kControlWord = 0x6040;        // sub 0, UNSIGNED16
inline constexpr uint16_t kStatusWord = 0x6041;         // sub 0, UNSIGNED16
inline constexpr uint16_t kDeviceMode = 0x6042;         // sub 0, INTEGER8: 1 = setpoint via bus
inline constexpr uint16_t kControlMode = 0x6043;        // sub 0, INTEGER8: 1 spool open loop, 2 spool closed loop, 5 p/Q
inline constexpr uint16_t kSplSetpoint = 0x6300;        // sub 1, INTEGER16
inline constexpr uint16_t kSplActualValue = 0x6301;     // sub 1, INTEGER16
inline constexpr uint16_t kSplReferenceValue = 0x6311;  // sub 1, INTEGER16, 16384
inline constexpr uint16_t kSplHoldSetpoint = 0x6314;    // sub 1, INTEGER16: the setpoint in HOLD
inline constexpr uint16_t kPrsSetpoint = 0x6380;        // sub 1, INTEGER16
inline constexpr uint16_t kPrsActualValue = 0x6381;     // sub 1, INTEGER16
inline constexpr uint8_t kValueSubindex = 1;

inline constexpr int16_t kFullScale = 16384;  // 100 % on the valves the project knows (0x6311:1)
inline constexpr double kSpoolScale = 1.0 / kFullScale;  // fraction of full opening per count

// Object 0x1000 (device type): the device profile number in the low 16 bits,
// 408 for this profile (401 is a generic I/O module, 402 a drive, ...).
inline constexpr uint16_t kProfileNumber = 408;
constexpr uint16_t device_profile(uint32_t device_type) { return static_cast<uint16_t>(device_type & 0xFFFF); }

inline constexpr int8_t kDeviceModeBus = 1;
inline constexpr int8_t kControlModeSpoolOpenLoop = 1;
inline constexpr int8_t kControlModeSpoolClosedLoop = 2;
inline constexpr int8_t kControlModePQ = 5;

// Control word bits (device state machine inputs) and status word bits 0..3.
inline constexpr uint16_t kBitDisabled = 0x0001;  // D
inline constexpr uint16_t kBitHold = 0x0002;      // H
inline constexpr uint16_t kBitActive = 0x0004;    // M
inline constexpr uint16_t kBitReady = 0x0008;     // R (control word: reset fault, on a rising edge)

inline constexpr uint16_t kControlActive = kBitDisabled | kBitHold | kBitActive;  // MHD = 111 -> ACTIVE
inline constexpr uint16_t kControlHold = kBitDisabled | kBitHold;                 // MHD = 011 -> HOLD
inline constexpr uint16_t kControlDisabled = kBitDisabled;                        // MHD = 001 -> DISABLED

enum class ValveState : uint8_t {
  kNotReady,  // RMHD 0000 (also FAULT_INIT)
  kInit,      // 1000
  kDisabled,  // 1001
  kHold,      // 1011
  kActive,    // 1111
  kFaultDisabled,  // 0001
  kFaultHold,      // 0011
  kFaultReaction,  // 0111
  kUndefined,
};

constexpr ValveState valve_state(uint16_t status_word) {
  switch (status_word & 0x0F) {
    case 0x0: return ValveState::kNotReady;
    case 0x8: return ValveState::kInit;
    case 0x9: return ValveState::kDisabled;
    case 0xB: return ValveState::kHold;
    case 0xF: return ValveState::kActive;
    case 0x1: return ValveState::kFaultDisabled;
    case 0x3: return ValveState::kFaultHold;
    case 0x7: return ValveState::kFaultReaction;
    default: return ValveState::kUndefined;
  }
}

constexpr const char* valve_state_name(ValveState s) {
  switch (s) {
    case ValveState::kNotReady: return "NOT_READY";
    case ValveState::kInit: return "INIT";
    case ValveState::kDisabled: return "DISABLED";
    case ValveState::kHold: return "HOLD";
    case ValveState::kActive: return "DEVICE_MODE_ACTIVE";
    case ValveState::kFaultDisabled: return "FAULT_DISABLED";
    case ValveState::kFaultHold: return "FAULT_HOLD";
    case ValveState::kFaultReaction: return "FAULT_REACTION";
    case ValveState::kUndefined: return "undefined";
  }
  return "?";
}

// The step of the DSM walk toward DEVICE MODE ACTIVE: the control word to
// send in state `s` (one state further up; a fault state gets a fault reset
// on top of the control word of the state it returns to, which makes a
// rising edge of bit 3 after a control word without it).
constexpr uint16_t control_word_toward_active(ValveState s) {
  switch (s) {
    case ValveState::kNotReady:
    case ValveState::kInit: return kControlDisabled;
    case ValveState::kDisabled: return kControlHold;
    case ValveState::kHold:
    case ValveState::kActive: return kControlActive;
    case ValveState::kFaultDisabled: return kControlDisabled | kBitReady;
    case ValveState::kFaultHold:
    case ValveState::kFaultReaction: return kControlHold | kBitReady;
    case ValveState::kUndefined: return kControlDisabled;
  }
  return kControlDisabled;
}

constexpr bool is_fault_state(ValveState s) {
  return s == ValveState::kFaultDisabled || s == ValveState::kFaultHold || s == ValveState::kFaultReaction;
}

// RPDO: control word (raw), spool setpoint (fraction of full opening with the
// default scale), and, if with_pressure, pressure setpoint (prs_scale per count).
inline PdoMapping setpoint_mapping(bool with_pressure, double spool_scale = kSpoolScale, double prs_scale = 1.0) {
  PdoMapping m;
  m.add({kControlWord, 0, PdoType::kU16, 1.0});
  m.add({kSplSetpoint, kValueSubindex, PdoType::kI16, spool_scale});
  if (with_pressure) m.add({kPrsSetpoint, kValueSubindex, PdoType::kI16, prs_scale});
  return m;
}

// TPDO: status word (raw), spool actual value and, if with_pressure, pressure actual value.
inline PdoMapping actual_mapping(bool with_pressure, double spool_scale = kSpoolScale, double prs_scale = 1.0) {
  PdoMapping m;
  m.add({kStatusWord, 0, PdoType::kU16, 1.0});
  m.add({kSplActualValue, kValueSubindex, PdoType::kI16, spool_scale});
  if (with_pressure) m.add({kPrsActualValue, kValueSubindex, PdoType::kI16, prs_scale});
  return m;
}

}  // namespace rigctl::canopen::cia408
