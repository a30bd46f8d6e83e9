// The loop's hand-off to a consumer thread: a bounded single-producer
// single-consumer queue (rt/spsc_queue.hpp) plus the producer's policy when it
// is full (rt/queue_full_policy.hpp), with the counts a run reports.
//
// Why the wait polls with a short sleep rather than waiting on a condition
// variable: the consumer side must stay free of any call that could wake or
// block the real-time producer, and kWait is only ever used where the
// producer has no deadline (simulated time), so a 50 us poll costs nothing
// that matters and leaves the CPU to the consumer on a 2-core machine.
#pragma once

#include <time.h>

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "rt/queue_full_policy.hpp"
#include "rt/spsc_queue.hpp"

namespace rigctl {

template <typename T>
class BoundedHandoff {
 public:
  BoundedHandoff(std::size_t capacity, QueueFullPolicy policy) : queue_(capacity), policy_(policy) {}

  // Set before the producer starts.
  void set_policy(QueueFullPolicy policy) { policy_ = policy; }
  QueueFullPolicy policy() const { return policy_; }
  std::size_t capacity() const { return queue_.capacity(); }

  // The consumer thread announces that it is draining (true after it
  // started, false before it stops). A waiting producer gives up once no
  // consumer runs: nothing would ever make room.
  void set_consumer_running(bool running) { consumer_running_.store(running, std::memory_order_release); }

  // Producer. kDrop never blocks. kWait returns once the item is queued, or
  // drops it when no consumer is running. Returns false on a drop (counted).
  bool push(const T& item) noexcept {
    if (queue_.try_push(item)) return true;
    if (policy_ == QueueFullPolicy::kWait) {
      waits_.store(waits_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      while (consumer_running_.load(std::memory_order_acquire)) {
        constexpr timespec kPoll{0, 50'000};
        nanosleep(&kPoll, nullptr);
        if (queue_.try_push(item)) return true;
      }
      if (queue_.try_push(item)) return true;  // the consumer's last drain may have made room
    }
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }

  // Consumer.
  bool pop(T& out) noexcept { return queue_.try_pop(out); }

  int64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  // Pushes that found the queue full and waited (kWait): how often the
  // consumer held the loop back.
  int64_t waits() const { return waits_.load(std::memory_order_relaxed); }

 private:
  SpscQueue<T> queue_;
  QueueFullPolicy policy_;
  std::atomic<bool> consumer_running_{false};
  std::atomic<int64_t> dropped_{0};
  std::atomic<int64_t> waits_{0};  // single writer (the producer)
};

}  // namespace rigctl
