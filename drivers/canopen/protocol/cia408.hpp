// CiA 408 (device profile fluid power technology: proportional valves and
// hydrostatic transmissions) objects a Moog-style servovalve uses, with the
// profile's default p/Q PDO mapping (RPDO: control word, spool setpoint,
// pressure setpoint; TPDO: status word, spool actual value, pressure actual
// value). Spool setpoint/actual value are INTEGER16 with 16384 = 100 % (the
// reference value object 0x6311 holds 16384). Pressure scaling depends on the
// valve's pressure reference, so it is a parameter.
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
inline constexpr uint16_t kPrsSetpoint = 0x6380;        // sub 1, INTEGER16
inline constexpr uint16_t kPrsActualValue = 0x6381;     // sub 1, INTEGER16
inline constexpr uint8_t kValueSubindex = 1;

inline constexpr int16_t kFullScale = 16384;  // 100 %
inline constexpr double kSpoolScale = 1.0 / kFullScale;  // fraction of full opening per count

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
    case ValveState::kActive: return "ACTIVE";
    case ValveState::kFaultDisabled: return "FAULT_DISABLED";
    case ValveState::kFaultHold: return "FAULT_HOLD";
    case ValveState::kFaultReaction: return "FAULT_REACTION";
    case ValveState::kUndefined: return "undefined";
  }
  return "?";
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
