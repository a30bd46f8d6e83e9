// One client's outgoing messages, all of them: telemetry data, answers,
// statuses, advertisements. Bounded in messages and in bytes. When full, the
// oldest data message goes (and is counted): a client that reads slowly is
// shown fresh data rather than an ever older backlog. Answers and statuses
// are never dropped: a queue that is full of them (a client that sends
// requests and does not read the answers) has overflowed, and the server
// closes that client with the reason. Not thread-safe: the server guards it
// with its own mutex.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>

namespace rigctl::foxglove {

struct QueuedMessage {
  bool data = true;               // message data (binary, opcode 1, framed when sent), or a message never dropped:
  bool binary = false;            //   a JSON text operation, or (binary) a framed answer to this client only
  uint32_t subscription = 0;      // data only
  uint64_t log_time_ns = 0;       // data only
  std::shared_ptr<const std::string> payload;  // data: the JSON message, shared by every client's queue
};

class ClientQueue {
 public:
  ClientQueue(std::size_t max_messages, std::size_t max_bytes)
      : max_messages_(max_messages == 0 ? 1 : max_messages), max_bytes_(max_bytes) {}

  // Drops the oldest data message when full (the new one when only text is queued).
  void push_data(uint32_t subscription, uint64_t log_time_ns, std::shared_ptr<const std::string> payload) {
    const std::size_t size = payload->size();
    if (!make_room(size)) {
      ++dropped_;
      return;
    }
    data_.push_back({next_++, QueuedMessage{true, true, subscription, log_time_ns, std::move(payload)}});
    bytes_ += size;
  }
  // False, and the queue is marked overflowed, when no room is left once
  // every data message has gone.
  bool push_text(std::shared_ptr<const std::string> text, bool binary = false) {
    const std::size_t size = text->size();
    if (overflowed_ || !make_room(size)) {
      overflowed_ = true;
      return false;
    }
    text_.push_back({next_++, QueuedMessage{false, binary, 0, 0, std::move(text)}});
    bytes_ += size;
    return true;
  }
  // The oldest message, data or text, in the order they were pushed.
  bool pop(QueuedMessage& out) {
    std::deque<Entry>* from = nullptr;
    if (!data_.empty() && (text_.empty() || data_.front().order < text_.front().order)) from = &data_;
    else if (!text_.empty()) from = &text_;
    if (from == nullptr) return false;
    out = std::move(from->front().message);
    from->pop_front();
    bytes_ -= out.payload->size();
    return true;
  }

  bool empty() const { return data_.empty() && text_.empty(); }
  std::size_t size() const { return data_.size() + text_.size(); }
  std::size_t bytes() const { return bytes_; }
  int64_t dropped() const { return dropped_; }
  bool overflowed() const { return overflowed_; }

 private:
  struct Entry {
    uint64_t order;
    QueuedMessage message;
  };
  bool fits(std::size_t n) const { return size() + 1 <= max_messages_ && bytes_ + n <= max_bytes_; }
  bool make_room(std::size_t n) {
    while (!fits(n) && !data_.empty()) {
      bytes_ -= data_.front().message.payload->size();
      data_.pop_front();
      ++dropped_;
    }
    return fits(n);
  }

  std::size_t max_messages_;
  std::size_t max_bytes_;
  std::deque<Entry> data_;
  std::deque<Entry> text_;
  std::size_t bytes_ = 0;
  uint64_t next_ = 0;
  int64_t dropped_ = 0;
  bool overflowed_ = false;
};

}  // namespace rigctl::foxglove
