// Lock-free hand-over of the latest spool actual value from the CAN I/O
// thread (one writer) to the real-time loop (readers): a sequence lock. The
// writer never waits; a reader retries a bounded number of times and then
// reports "no consistent value", which the driver treats as stale. All fields
// are atomics so there is no data race in the C++ sense, and the fences order
// them against the sequence counter.
#pragma once

#include <atomic>
#include <cstdint>

namespace rigctl {

struct ValveActual {
  int64_t rx_ns = 0;         // CLOCK_MONOTONIC time the TPDO was received
  uint64_t count = 0;        // TPDOs received so far; 0: none yet
  uint16_t status_word = 0;  // CiA 408 status word (0x6041)
  double spool = 0.0;        // fraction of rated opening
  double pressure = 0.0;     // Pa (0 when not mapped)
};

class LatestValveActual {
 public:
  void store(const ValveActual& a) noexcept {
    begin_store();
    finish_store(a);
  }
  // The two halves of store(). Between them readers get no copy: what a
  // writer preempted inside a store looks like to them (tests hold it open).
  // finish_store() alone (no store open) is a whole store: it cannot leave
  // the counter odd for good.
  void begin_store() noexcept {
    seq_.store(seq_.load(std::memory_order_relaxed) | 1U, std::memory_order_relaxed);  // odd: write in progress
    std::atomic_thread_fence(std::memory_order_release);
  }
  void finish_store(const ValveActual& a) noexcept {
    if ((seq_.load(std::memory_order_relaxed) & 1U) == 0) begin_store();
    rx_ns_.store(a.rx_ns, std::memory_order_relaxed);
    count_.store(a.count, std::memory_order_relaxed);
    status_word_.store(a.status_word, std::memory_order_relaxed);
    spool_.store(a.spool, std::memory_order_relaxed);
    pressure_.store(a.pressure, std::memory_order_relaxed);
    seq_.store(seq_.load(std::memory_order_relaxed) + 1, std::memory_order_release);  // even: done
  }

  // False when no consistent copy could be had in a few tries (the writer
  // kept writing): the caller treats that as a stale value.
  bool load(ValveActual& out) const noexcept {
    for (int attempt = 0; attempt < 8; ++attempt) {
      const uint32_t s1 = seq_.load(std::memory_order_acquire);
      if (s1 & 1U) continue;
      out.rx_ns = rx_ns_.load(std::memory_order_relaxed);
      out.count = count_.load(std::memory_order_relaxed);
      out.status_word = status_word_.load(std::memory_order_relaxed);
      out.spool = spool_.load(std::memory_order_relaxed);
      out.pressure = pressure_.load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s1) return true;
    }
    return false;
  }

 private:
  std::atomic<uint32_t> seq_{0};
  std::atomic<int64_t> rx_ns_{0};
  std::atomic<uint64_t> count_{0};
  std::atomic<uint16_t> status_word_{0};
  std::atomic<double> spool_{0.0};
  std::atomic<double> pressure_{0.0};
};

// One reader's view: the latest consistent copy, or, while the writer is
// inside a store, the copy this reader had before (`kept`, the reader's
// own). Its receive time then ages, so a writer that never finishes shows
// as a stale value, not as a missing one.
inline ValveActual load_or_keep(const LatestValveActual& latest, ValveActual& kept) noexcept {
  ValveActual a;
  if (latest.load(a)) kept = a;
  return kept;
}

static_assert(std::atomic<double>::is_always_lock_free);
static_assert(std::atomic<int64_t>::is_always_lock_free);

}  // namespace rigctl
