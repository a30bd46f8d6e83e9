// Bounded single-producer single-consumer ring buffer. The real-time loop
// pushes, the publisher thread pops; neither ever blocks or allocates after
// construction. A full queue rejects the push (the caller counts the drop):
// telemetry must never stall the control loop.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>

namespace rigctl {

template <typename T>
class SpscQueue {
 public:
  // capacity is rounded up to a power of two so the index wrap is a mask.
  explicit SpscQueue(std::size_t capacity) : mask_(round_up_pow2(capacity < 2 ? 2 : capacity) - 1),
                                             slots_(std::make_unique<T[]>(mask_ + 1)) {}

  std::size_t capacity() const { return mask_ + 1; }

  // Producer side.
  bool try_push(const T& item) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ > mask_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ > mask_) return false;
    }
    slots_[head & mask_] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer side.
  bool try_pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Approximate; exact only when the other side is idle.
  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

 private:
  static std::size_t round_up_pow2(std::size_t n) {
    std::size_t p = 1;
    while (p < n) p <<= 1;
    return p;
  }

  static constexpr std::size_t kLine = 64;  // keep producer and consumer indices on separate cache lines
  const std::size_t mask_;
  std::unique_ptr<T[]> slots_;
  alignas(kLine) std::atomic<std::size_t> head_{0};
  alignas(kLine) std::size_t tail_cache_ = 0;  // producer's copy of tail_
  alignas(kLine) std::atomic<std::size_t> tail_{0};
  alignas(kLine) std::size_t head_cache_ = 0;  // consumer's copy of head_
};

}  // namespace rigctl
