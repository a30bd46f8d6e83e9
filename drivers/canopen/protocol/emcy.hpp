// Emergency object (CiA 301): COB-ID 0x080+node, 8 bytes:
//   [0..1] emergency error code, little-endian  [2] error register (object 0x1001)
//   [3..7] manufacturer-specific error field.
// Error code 0x0000 is "error reset / no error".
#pragma once

#include <array>
#include <cstdint>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"

namespace rigctl::canopen {

// Error register (0x1001) bits.
namespace error_register {
inline constexpr uint8_t kGeneric = 0x01;
inline constexpr uint8_t kCurrent = 0x02;
inline constexpr uint8_t kVoltage = 0x04;
inline constexpr uint8_t kTemperature = 0x08;
inline constexpr uint8_t kCommunication = 0x10;
inline constexpr uint8_t kDeviceProfile = 0x20;
inline constexpr uint8_t kReserved = 0x40;
inline constexpr uint8_t kManufacturer = 0x80;
}  // namespace error_register

struct Emcy {
  uint8_t node = 0;
  uint16_t error_code = 0;
  uint8_t error_register = 0;
  std::array<uint8_t, 5> manufacturer{};
  bool is_reset() const { return error_code == 0x0000; }
  bool operator==(const Emcy&) const = default;
};

// COB-ID 0x080+node (1..127; 0x080 itself is SYNC) and length 8.
Malformed decode_emcy(const CanFrame& frame, Emcy& out);
// For the simulated valve (node 1..127).
CanFrame encode_emcy(const Emcy& e);

// Text of the CiA 301 emergency error code: the specific code where CiA 301
// names it (0x8110 CAN overrun, 0x8130 life guard / heartbeat error, ...),
// else its class (0x2xxx current, 0x3xxx voltage, ... 0xFFxx device specific),
// else "reserved".
const char* emcy_code_text(uint16_t code);

}  // namespace rigctl::canopen
