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

// The bits of an error register (0x1001) in words, "no error" for 0.
inline std::string error_register_text(uint8_t r) {
  static constexpr const char* kBits[8] = {"generic", "current", "voltage", "temperature",
                                           "communication", "device profile", "reserved", "manufacturer"};
  std::string s;
  for (int i = 0; i < 8; ++i) {
    if (r & (1U << i)) s += (s.empty() ? "" : ", ") + std::string(kBits[i]);
  }
  return s.empty() ? "no error" : s;
}

// "0.5 s" style, for times given in the config.
inline std::string seconds(double s) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g s", s);
  return buffer;
}

inline std::string milliseconds(int64_t ns) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f ms", static_cast<double>(ns) / 1e6);
  return buffer;
}

}  // namespace rigctl::canopen_text
