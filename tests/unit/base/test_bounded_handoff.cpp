// The loop's hand-off to a consumer thread: the SPSC ring itself, and what a
// full queue does under each policy. Order and counts are asserted, never a
// wall-clock window: a blocked producer cannot advance whatever the
// scheduler does, and every wait below ends on an event.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "rt/bounded_handoff.hpp"
#include "rt/spsc_queue.hpp"

namespace rigctl {
namespace {

// Generous: only a failing test ever waits this long.
constexpr auto kDeadline = std::chrono::seconds(60);

template <typename F>
bool eventually(F&& condition) {
  const auto end = std::chrono::steady_clock::now() + kDeadline;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

TEST(SpscQueue, CapacityIsRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(SpscQueue<int>(0).capacity(), 2u);
  EXPECT_EQ(SpscQueue<int>(5).capacity(), 8u);
  EXPECT_EQ(SpscQueue<int>(8).capacity(), 8u);
}

TEST(SpscQueue, KeepsOrderAcrossTheWrapAndRefusesWhenFull) {
  SpscQueue<int> q(4);
  int out = 0;
  EXPECT_FALSE(q.try_pop(out));
  for (int round = 0; round < 5; ++round) {  // 20 items through 4 slots: the indices wrap
    for (int i = 0; i < 4; ++i) ASSERT_TRUE(q.try_push(round * 4 + i));
    EXPECT_FALSE(q.try_push(-1)) << "a fifth item in four slots";
    EXPECT_EQ(q.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(q.try_pop(out));
      EXPECT_EQ(out, round * 4 + i);
    }
    EXPECT_FALSE(q.try_pop(out));
  }
}

TEST(SpscQueue, TwoThreadsPassEveryItemInOrder) {
  SpscQueue<int64_t> q(16);
  constexpr int64_t kItems = 200000;
  std::thread producer([&] {
    for (int64_t i = 0; i < kItems;) i += q.try_push(i) ? 1 : 0;
  });
  int64_t expected = 0, got = 0, out_of_order = 0;
  while (expected < kItems) {
    if (!q.try_pop(got)) continue;
    out_of_order += got != expected;
    ++expected;
  }
  producer.join();
  EXPECT_EQ(out_of_order, 0);
}

TEST(BoundedHandoff, DropPolicyNeverWaitsAndCountsWhatItDrops) {
  BoundedHandoff<int> h(4, QueueFullPolicy::kDrop);
  h.set_consumer_running(true);  // a consumer that has stalled (a blocked disk write, say)
  std::atomic<int> returned{0}, accepted{0};
  std::thread producer([&] {
    for (int i = 0; i < 10; ++i) {
      accepted += h.push(i) ? 1 : 0;
      ++returned;
    }
  });
  // Every push returns although nothing is ever popped.
  ASSERT_TRUE(eventually([&] { return returned.load() == 10; })) << "a push blocked under kDrop";
  producer.join();
  EXPECT_EQ(accepted.load(), 4);
  EXPECT_EQ(h.dropped(), 6);
  EXPECT_EQ(h.waits(), 0);
  int out = -1;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(h.pop(out));
    EXPECT_EQ(out, i) << "the oldest records are kept, the newest dropped";
  }
}

TEST(BoundedHandoff, WaitPolicyHoldsTheProducerUntilTheConsumerMakesRoom) {
  BoundedHandoff<int> h(2, QueueFullPolicy::kWait);
  h.set_consumer_running(true);
  constexpr int kItems = 2000;
  std::atomic<int> returned{0};
  std::thread producer([&] {
    for (int i = 0; i < kItems; ++i) {
      EXPECT_TRUE(h.push(i));
      ++returned;
    }
  });
  // The consumer has not popped: the producer is held at the third push.
  ASSERT_TRUE(eventually([&] { return h.waits() == 1; }));
  EXPECT_EQ(returned.load(), 2);
  // A slow consumer: pops one at a time. Everything arrives, in order.
  int next = 0, out = -1, out_of_order = 0;
  while (next < kItems) {
    if (!h.pop(out)) {
      std::this_thread::yield();
      continue;
    }
    out_of_order += out != next;
    ++next;
  }
  producer.join();
  EXPECT_EQ(out_of_order, 0);
  EXPECT_EQ(h.dropped(), 0);
  EXPECT_GE(h.waits(), 1);
}

TEST(BoundedHandoff, WaitPolicyWithoutARunningConsumerDropsRatherThanHangs) {
  BoundedHandoff<int> h(2, QueueFullPolicy::kWait);
  EXPECT_TRUE(h.push(1));
  EXPECT_TRUE(h.push(2));
  EXPECT_FALSE(h.push(3));  // no consumer: nothing would ever make room
  EXPECT_EQ(h.dropped(), 1);

  // A consumer that stops while the producer waits releases it.
  BoundedHandoff<int> g(2, QueueFullPolicy::kWait);
  g.set_consumer_running(true);
  g.push(1);
  g.push(2);
  std::atomic<bool> done{false};
  std::thread producer([&] {
    EXPECT_FALSE(g.push(3));
    done = true;
  });
  ASSERT_TRUE(eventually([&] { return g.waits() == 1; }));
  g.set_consumer_running(false);
  ASSERT_TRUE(eventually([&] { return done.load(); }));
  producer.join();
  EXPECT_EQ(g.dropped(), 1);
}

}  // namespace
}  // namespace rigctl
