// Operator commands for the tests: a fixed key, the policy the tests verify
// against, and commands built and signed as `rigctl cmd` would.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "rt/comms/operator_auth.hpp"

namespace rigctl::test {

constexpr int64_t kNow = 1'700'000'000'000'000;  // the rig's clock in the unit tests [us]

inline std::string hex(const uint8_t* p, std::size_t n) {
  std::string s;
  char b[3];
  for (std::size_t i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02x", p[i]);
    s += b;
  }
  return s;
}

inline OperatorKey key_of(uint8_t fill) {
  const std::vector<uint8_t> k(32, fill);
  return OperatorKey::from_bytes(k.data(), k.size());
}

inline CommandPolicy policy() {
  CommandPolicy p;
  p.max_age_us = 2'000'000;
  p.setpoint_min = -0.05;
  p.setpoint_max = 0.05;
  p.setpoint_unit = "m";
  return p;
}

inline operator_command_t command(const std::string& name, int64_t sequence, double value = 0.0, int64_t utime = kNow,
                           const std::string& sender = "alice@rigpc") {
  operator_command_t m;
  m.version = kOperatorWireVersion;
  m.sender = sender;
  m.sequence = sequence;
  m.utime = utime;
  m.command = name;
  m.value = value;
  std::memset(m.tag, 0, sizeof m.tag);
  return m;
}

inline std::vector<uint8_t> signed_bytes(operator_command_t m, const OperatorKey& key) {
  sign(m, key);
  return lcm_encode(m);
}

}  // namespace rigctl::test
