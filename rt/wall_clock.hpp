// The wall clock's time in LCM's utime unit (microseconds since the Unix
// epoch): the stamp on run logs, event lines and operator commands. Not
// for the loop's timing, which is CLOCK_MONOTONIC (rt/loop_clock.hpp).
#pragma once

#include <chrono>
#include <cstdint>

namespace rigctl {

inline int64_t wall_utime_now() noexcept {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rigctl
