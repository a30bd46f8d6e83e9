// Static PDO mapping (CiA 301): a PDO carries the mapped objects back to back,
// little-endian, from data byte 0, and its length is the sum of their sizes.
// Only whole-byte objects of 8, 16 and 32 bits are supported (all a CiA 408
// valve maps). Each entry has a scale: engineering value = raw * scale, so
// the CiA 408 spool setpoint/actual value (INTEGER16, 16384 = 100 %) read as a
// fraction of full opening with scale 1/16384.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "drivers/canopen/protocol/can_frame.hpp"
#include "drivers/canopen/protocol/frame_stats.hpp"

namespace rigctl::canopen {

enum class PdoType : uint8_t { kU8, kI8, kU16, kI16, kU32, kI32 };

constexpr uint8_t pdo_type_bits(PdoType t) {
  switch (t) {
    case PdoType::kU8:
    case PdoType::kI8: return 8;
    case PdoType::kU16:
    case PdoType::kI16: return 16;
    case PdoType::kU32:
    case PdoType::kI32: return 32;
  }
  return 0;
}
constexpr bool pdo_type_signed(PdoType t) {
  return t == PdoType::kI8 || t == PdoType::kI16 || t == PdoType::kI32;
}
int64_t pdo_type_min(PdoType t);
int64_t pdo_type_max(PdoType t);

struct PdoEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  PdoType type = PdoType::kI16;
  double scale = 1.0;  // engineering value per count; finite and non-zero
};

// CiA 301 mapping entry (objects 0x1600.., 0x1A00.. sub 1..8):
// index << 16 | subindex << 8 | bit length.
constexpr uint32_t pdo_mapping_value(const PdoEntry& e) {
  return (static_cast<uint32_t>(e.index) << 16) | (static_cast<uint32_t>(e.subindex) << 8) | pdo_type_bits(e.type);
}

class PdoMapping {
 public:
  static constexpr std::size_t kMaxEntries = 8;

  // Appends an entry; false (and nothing changes) when the PDO would exceed 8
  // bytes, the mapping is full, or the scale is not finite and non-zero.
  bool add(const PdoEntry& e);
  void clear() { count_ = 0; bits_ = 0; }

  std::size_t size() const { return count_; }
  uint8_t byte_length() const { return static_cast<uint8_t>(bits_ / 8); }
  const PdoEntry& operator[](std::size_t i) const { return entries_[i]; }
  std::span<const PdoEntry> entries() const { return {entries_.data(), count_}; }

 private:
  std::array<PdoEntry, kMaxEntries> entries_{};
  std::size_t count_ = 0;
  unsigned bits_ = 0;
};

struct PdoEncodeResult {
  bool ok = false;      // false: values.size() != mapping.size()
  uint8_t clamped = 0;  // values out of the type's range (saturated) or NaN (sent as 0)
};

// Raw (integer) values into a PDO on `cob_id`; values saturate to the type's range.
PdoEncodeResult encode_pdo_raw(const PdoMapping& m, uint32_t cob_id, std::span<const int64_t> raw, CanFrame& out);
// Engineering values into a PDO: raw = round(value / scale), saturated.
PdoEncodeResult encode_pdo(const PdoMapping& m, uint32_t cob_id, std::span<const double> values, CanFrame& out);

// A PDO into raw values (sign-extended for signed types) or engineering values
// (raw * scale). kNotDataFrame for RTR/EFF/ERR frames, kBadPdoLength when the
// length differs from the mapping's; nothing is written to `out` then. `out`
// takes at most its size; extra mapped values are not written.
Malformed decode_pdo_raw(const PdoMapping& m, const CanFrame& frame, std::span<int64_t> out);
Malformed decode_pdo(const PdoMapping& m, const CanFrame& frame, std::span<double> out);

}  // namespace rigctl::canopen
