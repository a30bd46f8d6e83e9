// Why a received frame was not used, and counters of it. The driver counts a
// malformed frame and drops it; it never throws or crashes on one. Every
// decoder in drivers/canopen returns one of these reasons.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace rigctl::canopen {

enum class Malformed : uint8_t {
  kNone = 0,       // the frame is fine
  kNotDataFrame,   // RTR, extended-format or SocketCAN error frame: CANopen here uses none
  kUnknownCobId,   // COB-ID of no service we know, node id 0 / out of range, or not this decoder's service
  kWrongLength,    // data length not the service's fixed length (or > 8)
  kBadContent,     // right length, but a field holds a value the service does not define
  kUnexpectedSdo,  // SDO response with no transfer pending, or from another node
  kBadPdoLength,   // PDO whose length does not match its mapping
};
inline constexpr std::size_t kMalformedReasons = 7;

constexpr const char* malformed_text(Malformed m) {
  switch (m) {
    case Malformed::kNone: return "ok";
    case Malformed::kNotDataFrame: return "not a standard data frame";
    case Malformed::kUnknownCobId: return "unknown COB-ID";
    case Malformed::kWrongLength: return "wrong length";
    case Malformed::kBadContent: return "bad content";
    case Malformed::kUnexpectedSdo: return "unexpected SDO";
    case Malformed::kBadPdoLength: return "bad PDO length";
  }
  return "?";
}

// Plain counters, owned by the one thread that receives frames; copy them out
// (a 64-byte value) to publish.
struct FrameStats {
  uint64_t accepted = 0;                             // frames used
  std::array<uint64_t, kMalformedReasons> by_reason{};  // [kNone] stays 0

  // Counts one received frame: accepted when m is kNone, else under its reason.
  constexpr void count(Malformed m) {
    const auto i = static_cast<std::size_t>(m);
    if (m == Malformed::kNone) {
      ++accepted;
    } else if (i < kMalformedReasons) {
      ++by_reason[i];
    }
  }
  constexpr uint64_t operator[](Malformed m) const {
    const auto i = static_cast<std::size_t>(m);
    return i < kMalformedReasons ? by_reason[i] : 0;
  }
  constexpr uint64_t malformed() const {
    uint64_t n = 0;
    for (std::size_t i = 1; i < kMalformedReasons; ++i) n += by_reason[i];
    return n;
  }
};

}  // namespace rigctl::canopen
