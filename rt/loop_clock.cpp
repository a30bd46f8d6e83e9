#include "rt/loop_clock.hpp"

#include <cerrno>
#include <ctime>

namespace rigctl {

int64_t MonotonicClock::now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void MonotonicClock::sleep_until(int64_t deadline_ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(deadline_ns % 1'000'000'000);
  // clock_nanosleep returns the error number instead of setting errno. With an
  // absolute deadline a signal (EINTR) is simply retried; EINVAL cannot happen
  // for a normalised timespec, and any other error falls through to the tick,
  // which then shows up as latency rather than hanging the loop.
  int rc;
  do {
    rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
  } while (rc == EINTR);
}

}  // namespace rigctl
