// Formatting of CANopen numbers for events and error messages (not real-time).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace rigctl::canopen_text {

// "0x6042" style, upper-case hex with at least `digits` digits.
inline std::string hex(uint32_t value, int digits) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%0*X", digits, static_cast<unsigned>(value));
  return buffer;
}

// Object dictionary address as "0x6042:00".
inline std::string od_address(uint16_t index, uint8_t subindex) {
  char buffer[16];
  std::snprintf(buffer, sizeof buffer, "0x%04X:%02X", static_cast<unsigned>(index), static_cast<unsigned>(subindex));
  return buffer;
}

inline std::string milliseconds(int64_t ns) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f ms", static_cast<double>(ns) / 1e6);
  return buffer;
}

}  // namespace rigctl::canopen_text
