// Bounded list of human-readable driver events, filled by the CAN I/O thread
// and drained by diagnostics(). Never touched by the real-time loop, so a
// mutex is fine. When full, the oldest event is dropped and counted: a
// flood of EMCYs must not grow memory without bound.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

namespace rigctl {

class BoundedEventLog {
 public:
  explicit BoundedEventLog(std::size_t capacity = 64) : capacity_(capacity) {}

  void push(std::string event) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (events_.size() == capacity_) {
      events_.pop_front();
      ++dropped_;
    }
    events_.push_back(std::move(event));
  }

  std::vector<std::string> drain() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> out(events_.begin(), events_.end());
    events_.clear();
    return out;
  }

  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }

 private:
  mutable std::mutex mutex_;
  std::size_t capacity_;
  std::deque<std::string> events_;
  uint64_t dropped_ = 0;
};

}  // namespace rigctl
