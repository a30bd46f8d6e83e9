// Wait-free hand-over of the newest value between exactly one writer thread
// and one reader thread (a triple buffer). Neither side ever blocks, retries,
// allocates or makes a system call, whatever the other side is doing: the
// real-time loop reads the Modbus I/O thread's samples and posts its outputs
// through two of these, so a Modbus timeout can never stall a tick.
//
// Why not a seqlock: its reader retries while the writer is mid-copy, so a
// writer preempted in the middle of a copy makes the reader spin. Why not a
// mutex: priority inversion against the SCHED_FIFO loop. A triple buffer
// costs two spare copies of T and one atomic exchange per hand-over.
#pragma once

#include <atomic>
#include <cstdint>

namespace rigctl {

template <typename T>
class TripleBuffer {
 public:
  // All three slots start as `initial`, so the reader sees it until the first publish.
  explicit TripleBuffer(const T& initial = T{}) : slots_{initial, initial, initial} {}

  // Writer: the slot to fill. It holds an older value, not the last one
  // published: write every field before publish().
  T& write_slot() noexcept { return slots_[back_]; }

  // Writer: makes write_slot() the newest value; takes a free slot for the next write.
  void publish() noexcept {
    back_ = middle_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel) & kIndex;
  }

  // Reader: the newest published value (or the previous one when nothing new
  // was published). Stays valid and unchanged until the reader's next read().
  const T& read() noexcept {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    }
    return slots_[front_];
  }

 private:
  static constexpr uint8_t kIndex = 0x3;
  static constexpr uint8_t kFresh = 0x4;  // set in middle_ when it holds a value the reader has not taken
  static_assert(std::atomic<uint8_t>::is_always_lock_free);

  static constexpr std::size_t kLine = 64;
  T slots_[3];
  alignas(kLine) uint8_t back_ = 0;   // writer's slot
  alignas(kLine) std::atomic<uint8_t> middle_{1};
  alignas(kLine) uint8_t front_ = 2;  // reader's slot
};

}  // namespace rigctl
