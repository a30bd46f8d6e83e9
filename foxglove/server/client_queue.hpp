// One client's outgoing messages: bounded, and when full the oldest message
// goes (and is counted), so a client that stops reading costs a fixed amount
// of memory and never holds up the publisher or the other clients. Not
// thread-safe: the server guards it with its own mutex.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>

namespace rigctl::foxglove {

struct QueuedMessage {
  uint32_t subscription = 0;
  uint64_t log_time_ns = 0;
  std::shared_ptr<const std::string> payload;  // shared by every client's queue
};

class ClientQueue {
 public:
  explicit ClientQueue(std::size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  void push(QueuedMessage m) {
    if (queue_.size() >= capacity_) {
      queue_.pop_front();
      ++dropped_;
    }
    queue_.push_back(std::move(m));
  }
  bool pop(QueuedMessage& out) {
    if (queue_.empty()) return false;
    out = std::move(queue_.front());
    queue_.pop_front();
    return true;
  }
  bool empty() const { return queue_.empty(); }
  std::size_t size() const { return queue_.size(); }
  int64_t dropped() const { return dropped_; }

 private:
  std::size_t capacity_;
  std::deque<QueuedMessage> queue_;
  int64_t dropped_ = 0;
};

}  // namespace rigctl::foxglove
