// Where the loop gets its time and how it waits. The real rig uses the
// monotonic clock with absolute-deadline sleeps; --fast uses a virtual clock
// that jumps to each deadline, so simulated time runs as fast as the CPU.
#pragma once

#include <cstdint>

namespace rigctl {

class LoopClock {
 public:
  virtual ~LoopClock() = default;
  virtual int64_t now_ns() noexcept = 0;
  // Returns once now_ns() >= deadline_ns (at once if already past).
  virtual void sleep_until(int64_t deadline_ns) noexcept = 0;
};

// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME): no drift, no
// accumulation of sleep errors.
class MonotonicClock final : public LoopClock {
 public:
  int64_t now_ns() noexcept override;
  void sleep_until(int64_t deadline_ns) noexcept override;
};

// Virtual time: sleeping moves time to the deadline, work takes no time.
class VirtualClock final : public LoopClock {
 public:
  int64_t now_ns() noexcept override { return now_; }
  void sleep_until(int64_t deadline_ns) noexcept override {
    if (deadline_ns > now_) now_ = deadline_ns;
  }

 private:
  int64_t now_ = 0;
};

}  // namespace rigctl
