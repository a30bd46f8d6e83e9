// PDO set-up by SDO (CiA 301): the objects that describe a PDO, and the
// sequence that changes one safely. For PDO n (1..4):
//   communication parameter  RPDO 0x1400+n-1, TPDO 0x1800+n-1
//     sub 1 COB-ID (UNSIGNED32: bit 31 set = PDO not valid, bit 30 set = no
//           RTR, bit 29 = 29-bit id, bits 0..10 the 11-bit id)
//     sub 2 transmission type (UNSIGNED8: 254/255 event-driven; an RPDO of
//           either is acted on as it arrives)
//     sub 5 event timer (UNSIGNED16 ms: a TPDO is sent at least this often;
//           for an RPDO it is the deadline by which the next must arrive,
//           after which the device reports an RPDO time-out; 0 = off)
//   mapping parameter  RPDO 0x1600+n-1, TPDO 0x1A00+n-1
//     sub 0 number of mapped objects, sub 1..8 index << 16 | sub << 8 | bits
// A mapping may only be changed while the PDO is not valid and its count is
// 0, hence the sequence: disable (COB-ID bit 31), clear the count, write the
// entries, set the count, set transmission type and event timer, enable.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "drivers/canopen/protocol/pdo.hpp"

namespace rigctl::canopen {

inline constexpr uint32_t kPdoCobInvalid = 0x80000000U;  // COB-ID bit 31: PDO not valid
inline constexpr uint32_t kPdoCobNoRtr = 0x40000000U;    // COB-ID bit 30: no RTR allowed
inline constexpr uint32_t kPdoCobIdMask = 0x000007FFU;
inline constexpr uint8_t kPdoCobIdSub = 1;
inline constexpr uint8_t kPdoTransmissionTypeSub = 2;
inline constexpr uint8_t kPdoEventTimerSub = 5;
inline constexpr uint8_t kTransmissionEventDriven = 255;  // device-profile event: sent by the event timer, acted on at once

enum class PdoDirection : uint8_t {
  kReceive,   // RPDO: the device receives it (our setpoint)
  kTransmit,  // TPDO: the device sends it (its actual value)
};

constexpr uint16_t pdo_communication_index(PdoDirection d, int n) {
  return static_cast<uint16_t>((d == PdoDirection::kReceive ? 0x1400 : 0x1800) + n - 1);
}
constexpr uint16_t pdo_mapping_index(PdoDirection d, int n) {
  return static_cast<uint16_t>((d == PdoDirection::kReceive ? 0x1600 : 0x1A00) + n - 1);
}

// One mapping entry's fields (the inverse of pdo_mapping_value).
struct PdoMappingField {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t bits = 0;
};
constexpr PdoMappingField decode_pdo_mapping_value(uint32_t v) {
  return {static_cast<uint16_t>(v >> 16), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v)};
}

// What one PDO should be.
struct PdoSetup {
  PdoDirection direction = PdoDirection::kReceive;
  int number = 1;           // 1..4
  uint32_t cob_id = 0;      // 11-bit identifier
  PdoMapping mapping;
  uint8_t transmission_type = kTransmissionEventDriven;
  uint16_t event_timer_ms = 0;
};

// "RPDO1" / "TPDO2".
std::string pdo_name(const PdoSetup& s);

// One SDO access of the set-up: a write, or (in read_back) what must be read.
struct PdoObjectValue {
  std::string what;  // e.g. "RPDO1 mapping entry 2 (0x63000110)"
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t size = 0;       // bytes
  uint32_t value = 0;
  uint32_t compare_mask = 0xFFFFFFFFU;  // read back: the bits that must match
};

// The CiA 301 sequence of SDO writes for `s`. `cob_as_read` is the
// device's COB-ID entry before the change: its bits 29 and 30 are kept.
std::vector<PdoObjectValue> pdo_setup_writes(const PdoSetup& s, uint32_t cob_as_read);

// What the device must hold afterwards: the count, each entry, transmission
// type, event timer and the COB-ID (valid, our identifier).
std::vector<PdoObjectValue> pdo_setup_read_back(const PdoSetup& s);

}  // namespace rigctl::canopen
