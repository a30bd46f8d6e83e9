// At most N log lines a second, the rest counted and summarised once the
// second is over: every refusal is counted, but a flood of forged or
// careless messages must not fill the disk (the command receiver's
// rejections, the console's and the Foxglove server's refusals). Not
// thread-safe: each user guards its own.
#pragma once

#include <cstdint>

namespace rigctl {

class LogRateLimit {
 public:
  explicit LogRateLimit(int per_second) : per_second_(per_second) {}

  // Whether a line at `now_us` may be written. When a new second begins
  // and lines were held back in the last, `*suppressed` is set to their
  // count (to be written as one summary line first), else to 0.
  bool admit(int64_t now_us, uint64_t* suppressed) {
    *suppressed = 0;
    if (now_us - window_start_ >= 1'000'000 || now_us < window_start_) {
      *suppressed = held_back_;
      window_start_ = now_us;
      written_ = 0;
      held_back_ = 0;
    }
    if (written_ >= per_second_) {
      ++held_back_;
      return false;
    }
    ++written_;
    return true;
  }

 private:
  int per_second_;
  int64_t window_start_ = INT64_MIN / 2;  // the first line opens a window
  int written_ = 0;
  uint64_t held_back_ = 0;
};

}  // namespace rigctl
