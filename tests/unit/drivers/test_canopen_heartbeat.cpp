// Heartbeat consumer and producer (drivers/canopen/nmt.*) with injected
// times: timeouts exactly at the boundary, recovery, a valve that resets
// itself while operational, and the producer's period.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

#include "drivers/canopen/protocol/nmt.hpp"

using namespace rigctl::canopen;
using Event = HeartbeatConsumer::Event;
using Status = HeartbeatConsumer::Status;

namespace {
constexpr uint8_t kNode = 0x21;
constexpr int64_t kMs = 1'000'000;
constexpr int64_t kConsumerTime = 150 * kMs;
constexpr int64_t kT0 = 5'000 * kMs;

Heartbeat hb(NmtState s, uint8_t node = kNode) { return {node, s}; }
}  // namespace

TEST(HeartbeatConsumer, NeverSeenNeverTimesOut) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  EXPECT_EQ(c.status(), Status::kNeverSeen);
  EXPECT_EQ(c.poll(kT0), Event::kNone);
  EXPECT_EQ(c.poll(std::numeric_limits<int64_t>::max()), Event::kNone);
  EXPECT_EQ(c.status(), Status::kNeverSeen);
  EXPECT_EQ(c.timeouts(), 0U);
}

TEST(HeartbeatConsumer, TimeoutExactlyAtTheBoundary) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kPreOperational), kT0), Event::kFirstSeen);
  EXPECT_EQ(c.status(), Status::kAlive);
  EXPECT_EQ(c.last_heartbeat_ns(), kT0);
  EXPECT_EQ(c.poll(kT0 + kConsumerTime - 1), Event::kNone);
  EXPECT_EQ(c.poll(kT0 + kConsumerTime), Event::kNone);  // exactly the consumer time: still alive
  EXPECT_TRUE(c.alive());
  EXPECT_EQ(c.poll(kT0 + kConsumerTime + 1), Event::kTimedOut);
  EXPECT_EQ(c.status(), Status::kTimedOut);
  EXPECT_EQ(c.poll(kT0 + kConsumerTime + 2), Event::kNone);  // reported once
  EXPECT_EQ(c.poll(kT0 + 100 * kConsumerTime), Event::kNone);
  EXPECT_EQ(c.timeouts(), 1U);
  EXPECT_EQ(c.last_heartbeat_ns(), kT0);  // the time of the last heartbeat stays
}

TEST(HeartbeatConsumer, HeartbeatAtTheBoundaryRestartsTheWindow) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  c.on_heartbeat(hb(NmtState::kOperational), kT0);
  EXPECT_EQ(c.poll(kT0 + kConsumerTime), Event::kNone);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational), kT0 + kConsumerTime), Event::kNone);
  EXPECT_EQ(c.poll(kT0 + 2 * kConsumerTime), Event::kNone);
  EXPECT_EQ(c.poll(kT0 + 2 * kConsumerTime + 1), Event::kTimedOut);
}

TEST(HeartbeatConsumer, RecoversAfterTimeout) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  c.on_heartbeat(hb(NmtState::kOperational), kT0);
  ASSERT_EQ(c.poll(kT0 + kConsumerTime + 1), Event::kTimedOut);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational), kT0 + 500 * kMs), Event::kRecovered);
  EXPECT_TRUE(c.alive());
  EXPECT_EQ(c.poll(kT0 + 500 * kMs + kConsumerTime), Event::kNone);
  EXPECT_EQ(c.poll(kT0 + 500 * kMs + kConsumerTime + 1), Event::kTimedOut);
  EXPECT_EQ(c.timeouts(), 2U);
}

TEST(HeartbeatConsumer, StateChangesAndOtherNodes) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational, kNode + 1), kT0), Event::kNone);
  EXPECT_EQ(c.status(), Status::kNeverSeen);  // someone else's heartbeat
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kPreOperational), kT0), Event::kFirstSeen);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kPreOperational), kT0 + 100 * kMs), Event::kNone);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational), kT0 + 200 * kMs), Event::kStateChanged);
  EXPECT_EQ(c.last_state(), NmtState::kOperational);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kStopped), kT0 + 300 * kMs), Event::kStateChanged);
  EXPECT_EQ(c.last_state(), NmtState::kStopped);
  // Other node's heartbeats do not keep this one alive.
  c.on_heartbeat(hb(NmtState::kOperational, kNode + 1), kT0 + 400 * kMs);
  EXPECT_EQ(c.poll(kT0 + 300 * kMs + kConsumerTime + 1), Event::kTimedOut);
}

TEST(HeartbeatConsumer, BootUpAfterOperationalIsAReset) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0), Event::kFirstSeen);
  EXPECT_FALSE(c.reset_after_operational());
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kPreOperational), kT0 + 10 * kMs), Event::kStateChanged);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational), kT0 + 20 * kMs), Event::kStateChanged);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kOperational), kT0 + 120 * kMs), Event::kNone);
  // The valve resets by itself: boot-up while we thought it was operational.
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0 + 130 * kMs), Event::kResetAfterOperational);
  EXPECT_TRUE(c.reset_after_operational());
  EXPECT_EQ(c.last_state(), NmtState::kBootUp);
  EXPECT_EQ(c.boot_ups(), 2U);
  // Sticky until cleared, even once it is back in pre-operational.
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kPreOperational), kT0 + 140 * kMs), Event::kStateChanged);
  EXPECT_TRUE(c.reset_after_operational());
  c.clear_reset();
  EXPECT_FALSE(c.reset_after_operational());
}

TEST(HeartbeatConsumer, BootUpAfterOperationalEvenWhenTimedOut) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  c.on_heartbeat(hb(NmtState::kOperational), kT0);
  ASSERT_EQ(c.poll(kT0 + kConsumerTime + 1), Event::kTimedOut);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0 + 2 * kConsumerTime), Event::kResetAfterOperational);
  EXPECT_TRUE(c.alive());
}

TEST(HeartbeatConsumer, BootUpWithoutOperationIsNotAReset) {
  // The driver resets the node during configuration: pre-operational -> boot-up is expected.
  HeartbeatConsumer c(kNode, kConsumerTime);
  c.on_heartbeat(hb(NmtState::kPreOperational), kT0);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0 + 10 * kMs), Event::kBootUp);
  EXPECT_FALSE(c.reset_after_operational());
  // Operational, then stopped, then boot-up: it had been operational since its last boot.
  c.on_heartbeat(hb(NmtState::kOperational), kT0 + 20 * kMs);
  c.on_heartbeat(hb(NmtState::kStopped), kT0 + 30 * kMs);
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0 + 40 * kMs), Event::kResetAfterOperational);
  // reset() forgets the node (the driver resets it on purpose).
  c.reset();
  EXPECT_EQ(c.status(), Status::kNeverSeen);
  EXPECT_FALSE(c.reset_after_operational());
  EXPECT_EQ(c.on_heartbeat(hb(NmtState::kBootUp), kT0 + 50 * kMs), Event::kFirstSeen);
}

TEST(HeartbeatConsumer, ZeroConsumerTimeDisablesTimeout) {
  HeartbeatConsumer c(kNode, 0);
  c.on_heartbeat(hb(NmtState::kOperational), kT0);
  EXPECT_EQ(c.poll(kT0 + 1'000'000 * kMs), Event::kNone);
  EXPECT_TRUE(c.alive());
}

TEST(HeartbeatConsumer, TimeGoingBackwardsOrExtremeTimesAreSafe) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  c.on_heartbeat(hb(NmtState::kOperational), kT0);
  EXPECT_EQ(c.poll(kT0 - 10 * kConsumerTime), Event::kNone);
  EXPECT_EQ(c.poll(std::numeric_limits<int64_t>::min()), Event::kNone);
  HeartbeatConsumer d(kNode, kConsumerTime);
  d.on_heartbeat(hb(NmtState::kOperational), std::numeric_limits<int64_t>::min());
  EXPECT_EQ(d.poll(std::numeric_limits<int64_t>::max()), Event::kTimedOut);  // no overflow
}

TEST(HeartbeatConsumer, FedFromDecodedFrames) {
  HeartbeatConsumer c(kNode, kConsumerTime);
  int64_t t = kT0;
  for (NmtState s : {NmtState::kBootUp, NmtState::kPreOperational, NmtState::kOperational}) {
    Heartbeat h;
    ASSERT_EQ(decode_heartbeat(encode_heartbeat(kNode, s), h), Malformed::kNone);
    c.on_heartbeat(h, t);
    t += 100 * kMs;
  }
  EXPECT_EQ(c.last_state(), NmtState::kOperational);
  EXPECT_EQ(c.last_heartbeat_ns(), kT0 + 200 * kMs);
}

TEST(HeartbeatConsumer, ObjectEntryLayout) {
  // 0x1016 sub n: producer node in bits 16..23, time in ms in bits 0..15.
  EXPECT_EQ(consumer_heartbeat_entry(0x7F, 300), 0x007F012CU);
  EXPECT_EQ(consumer_heartbeat_entry(1, 0xFFFF), 0x0001FFFFU);
}

// ---------------------------------------------------------------- producer

TEST(HeartbeatProducer, PeriodOnAFixedGrid) {
  constexpr int64_t kPeriod = 100 * kMs;
  HeartbeatProducer p(kNode, kPeriod);
  EXPECT_FALSE(p.due(kT0));  // not started
  EXPECT_FALSE(p.poll(kT0, NmtState::kOperational).has_value());
  const CanFrame boot = p.boot_up();
  EXPECT_EQ(boot.can_id, 0x700U + kNode);
  ASSERT_EQ(boot.len, 1);
  EXPECT_EQ(boot.data[0], 0x00);

  p.start(kT0);
  EXPECT_TRUE(p.due(kT0));
  auto f = p.poll(kT0, NmtState::kPreOperational);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->can_id, 0x700U + kNode);
  ASSERT_EQ(f->len, 1);
  EXPECT_EQ(f->data[0], 0x7F);
  EXPECT_EQ(p.next_due_ns(), kT0 + kPeriod);
  EXPECT_FALSE(p.poll(kT0 + kPeriod - 1, NmtState::kPreOperational).has_value());
  f = p.poll(kT0 + kPeriod, NmtState::kOperational);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->data[0], 0x05);
  EXPECT_EQ(p.next_due_ns(), kT0 + 2 * kPeriod);
  // Polled 3 ms late: no drift, the next one is still on the grid.
  ASSERT_TRUE(p.poll(kT0 + 2 * kPeriod + 3 * kMs, NmtState::kOperational).has_value());
  EXPECT_EQ(p.next_due_ns(), kT0 + 3 * kPeriod);
}

TEST(HeartbeatProducer, LateCallerGetsOneFrameNotABurst) {
  constexpr int64_t kPeriod = 100 * kMs;
  HeartbeatProducer p(kNode, kPeriod);
  p.start(kT0);
  ASSERT_TRUE(p.poll(kT0, NmtState::kOperational));
  const int64_t late = kT0 + 350 * kMs;  // 2.5 periods after the one due at kT0 + 100 ms
  ASSERT_TRUE(p.poll(late, NmtState::kOperational));
  EXPECT_FALSE(p.poll(late, NmtState::kOperational));
  EXPECT_EQ(p.next_due_ns(), kT0 + 400 * kMs);
}

TEST(HeartbeatProducer, CountOverOneSecondOfMillisecondTicks) {
  constexpr int64_t kPeriod = 100 * kMs;
  HeartbeatProducer p(kNode, kPeriod);
  p.start(kT0);
  std::vector<int64_t> sent;
  for (int64_t t = kT0; t < kT0 + 1000 * kMs; t += kMs) {
    if (p.poll(t, NmtState::kOperational)) sent.push_back(t);
  }
  ASSERT_EQ(sent.size(), 10U);
  for (std::size_t i = 0; i < sent.size(); ++i) EXPECT_EQ(sent[i], kT0 + static_cast<int64_t>(i) * kPeriod);
}

TEST(HeartbeatProducer, ZeroPeriodNeverSends) {
  HeartbeatProducer p(kNode, 0);
  p.start(kT0);
  EXPECT_FALSE(p.due(kT0));
  EXPECT_FALSE(p.poll(kT0 + 1000 * kMs, NmtState::kOperational).has_value());
}

TEST(HeartbeatProducer, ProducerKeepsConsumerAliveUntilItStops) {
  constexpr int64_t kPeriod = 100 * kMs;
  HeartbeatProducer p(kNode, kPeriod);
  HeartbeatConsumer c(kNode, kConsumerTime);
  p.start(kT0);
  int64_t last_sent = 0;
  for (int64_t t = kT0; t <= kT0 + 2000 * kMs; t += kMs) {
    if (t < kT0 + 1000 * kMs) {
      if (auto f = p.poll(t, NmtState::kOperational)) {
        Heartbeat h;
        ASSERT_EQ(decode_heartbeat(*f, h), Malformed::kNone);
        c.on_heartbeat(h, t);
        last_sent = t;
      }
    }
    const Event e = c.poll(t);
    if (t <= last_sent + kConsumerTime) {
      ASSERT_EQ(e, Event::kNone) << (t - kT0) / kMs << " ms";
    } else if (t == last_sent + kConsumerTime + kMs) {
      ASSERT_EQ(e, Event::kTimedOut) << (t - kT0) / kMs << " ms";
    }
  }
  EXPECT_EQ(last_sent, kT0 + 900 * kMs);
  EXPECT_EQ(c.timeouts(), 1U);
  EXPECT_EQ(c.status(), Status::kTimedOut);
}
