// One classic CAN frame, byte-compatible with Linux `struct can_frame`
// (<linux/can.h>), so that read()/write() on a CAN_RAW socket (or on the
// SOCK_SEQPACKET socket the tests use instead) move it as is. Usable without
// <linux/can.h>: the flag constants are repeated here and checked against the
// kernel's in tests/unit/drivers/test_canopen_frames.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <type_traits>

namespace rigctl::canopen {

inline constexpr uint32_t kCanEffFlag = 0x80000000U;  // extended (29-bit) frame format
inline constexpr uint32_t kCanRtrFlag = 0x40000000U;  // remote transmission request
inline constexpr uint32_t kCanErrFlag = 0x20000000U;  // error message frame (SocketCAN)
inline constexpr uint32_t kCanSffMask = 0x000007FFU;  // 11-bit identifier
inline constexpr uint32_t kCanEffMask = 0x1FFFFFFFU;  // 29-bit identifier
inline constexpr uint8_t kCanMaxDataLen = 8;

struct CanFrame {
  uint32_t can_id = 0;  // identifier plus the EFF/RTR/ERR flag bits above
  uint8_t len = 0;      // data length 0..8 (the kernel's len / can_dlc)
  uint8_t pad = 0;      // __pad
  uint8_t res0 = 0;     // __res0
  uint8_t len8_dlc = 0; // raw DLC 9..15 for len 8 (unused here, kept 0)
  alignas(8) uint8_t data[kCanMaxDataLen] = {};

  // 11-bit identifier (the CANopen COB-ID) of a standard frame.
  constexpr uint32_t id() const { return can_id & kCanSffMask; }
  // A standard-format data frame: no EFF, RTR or ERR flag. CANopen (CiA 301
  // pre-defined connection set) only uses these.
  constexpr bool is_standard_data() const { return (can_id & (kCanEffFlag | kCanRtrFlag | kCanErrFlag)) == 0; }
};

static_assert(sizeof(CanFrame) == 16, "CanFrame must match struct can_frame");
static_assert(offsetof(CanFrame, can_id) == 0);
static_assert(offsetof(CanFrame, len) == 4);
static_assert(offsetof(CanFrame, pad) == 5);
static_assert(offsetof(CanFrame, res0) == 6);
static_assert(offsetof(CanFrame, len8_dlc) == 7);
static_assert(offsetof(CanFrame, data) == 8);
static_assert(std::is_standard_layout_v<CanFrame>);
static_assert(std::is_trivially_copyable_v<CanFrame>);

// A standard data frame with the given COB-ID and bytes (at most 8 are used).
constexpr CanFrame make_frame(uint32_t cob_id, std::initializer_list<uint8_t> bytes) {
  CanFrame f;
  f.can_id = cob_id & kCanSffMask;
  uint8_t n = 0;
  for (uint8_t b : bytes) {
    if (n == kCanMaxDataLen) break;
    f.data[n++] = b;
  }
  f.len = n;
  return f;
}

// Little-endian field access (CANopen is little-endian on the wire).
constexpr uint16_t get_u16le(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
constexpr uint32_t get_u32le(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}
constexpr void put_u16le(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
constexpr void put_u32le(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace rigctl::canopen
