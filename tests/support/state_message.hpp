// A rig's STATE message as the publisher sends it, for the tests of what
// clients are told about it (statuses).
#pragma once

#include <cstdint>
#include <string>

#include "rigctl/state_t.hpp"

namespace rigctl::test {

inline rigctl::state_t state_message(const std::string& safety_state, const std::string& event = "",
                                     const std::string& message = "", int64_t tick = 0) {
  rigctl::state_t st{};
  st.utime = 1'700'000'000'000'000 + tick * 2500;  // a run's start plus 2.5 ms a tick
  st.tick = tick;
  st.t = static_cast<double>(tick) * 0.0025;
  st.state = "running";
  st.safety_state = safety_state;
  st.event = event;
  st.message = message;
  return st;
}

}  // namespace rigctl::test
