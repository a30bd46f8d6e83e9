// TripleBuffer: the wait-free newest-value hand-over between the Modbus I/O
// thread and the loop. The single-thread tests pin the semantics (what the
// reader sees after which publishes); the two-thread test checks that a read
// is never a mix of two writes and never goes back in time, whatever the
// interleaving the scheduler happens to produce. No test waits on the clock.
#include "drivers/modbus/modbus_triple_buffer.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>

namespace rigctl {
namespace {

// A value whose fields must agree: a torn read (half of one write, half of
// another) shows up as fields that do not match the sequence number.
struct Stamped {
  uint64_t seq = 0;
  std::array<uint64_t, 15> copies{};  // 128 bytes in all: a copy spans several cache lines

  static Stamped of(uint64_t seq) {
    Stamped s;
    s.seq = seq;
    for (std::size_t i = 0; i < s.copies.size(); ++i) s.copies[i] = seq * 31 + i;
    return s;
  }
  bool consistent() const {
    for (std::size_t i = 0; i < copies.size(); ++i)
      if (copies[i] != seq * 31 + i) return false;
    return true;
  }
};

TEST(TripleBuffer, ReaderSeesTheInitialValueUntilTheFirstPublish) {
  TripleBuffer<int> buffer(7);
  EXPECT_EQ(buffer.read(), 7);
  buffer.write_slot() = 8;  // written but not published
  EXPECT_EQ(buffer.read(), 7);
  buffer.publish();
  EXPECT_EQ(buffer.read(), 8);
}

TEST(TripleBuffer, ReaderGetsTheNewestOfSeveralPublishes) {
  TripleBuffer<int> buffer(0);
  for (int v = 1; v <= 5; ++v) {
    buffer.write_slot() = v;
    buffer.publish();
  }
  EXPECT_EQ(buffer.read(), 5);
}

TEST(TripleBuffer, ReadWithoutNewPublishRepeatsTheLastValue) {
  TripleBuffer<int> buffer(0);
  buffer.write_slot() = 3;
  buffer.publish();
  EXPECT_EQ(buffer.read(), 3);
  EXPECT_EQ(buffer.read(), 3);
}

TEST(TripleBuffer, WritesDoNotTouchTheSlotTheReaderHolds) {
  TripleBuffer<int> buffer(0);
  buffer.write_slot() = 1;
  buffer.publish();
  const int& held = buffer.read();
  ASSERT_EQ(held, 1);
  // The writer keeps publishing while the reader still holds its slot: with
  // three slots the writer can always find one that is not the reader's.
  for (int v = 2; v <= 10; ++v) {
    buffer.write_slot() = v;
    buffer.publish();
    EXPECT_EQ(held, 1) << "writer overwrote the reader's slot at publish " << v;
  }
  EXPECT_EQ(buffer.read(), 10);
}

TEST(TripleBuffer, WriteSlotIsNeverTheReadersSlot) {
  TripleBuffer<int> buffer(0);
  for (int round = 0; round < 20; ++round) {
    const int* reader_slot = &buffer.read();
    EXPECT_NE(&buffer.write_slot(), reader_slot) << "round " << round;
    buffer.write_slot() = round;
    buffer.publish();
  }
}

TEST(TripleBuffer, ConcurrentReadsAreWholeAndInOrder) {
  constexpr uint64_t kLast = 200000;
  TripleBuffer<Stamped> buffer(Stamped::of(0));

  std::thread writer([&] {
    for (uint64_t seq = 1; seq <= kLast; ++seq) {
      buffer.write_slot() = Stamped::of(seq);
      buffer.publish();
    }
  });

  // The reader ends when it has seen the writer's last value, which it must
  // (the last publish leaves it fresh): no clock, no time-out to tune.
  uint64_t previous = 0, reads = 0, torn = 0, backwards = 0;
  while (previous != kLast) {
    const Stamped& s = buffer.read();
    ++reads;
    if (!s.consistent()) ++torn;
    if (s.seq < previous) ++backwards;
    previous = s.seq > previous ? s.seq : previous;
  }
  writer.join();

  EXPECT_EQ(torn, 0u) << "of " << reads << " reads";
  EXPECT_EQ(backwards, 0u) << "of " << reads << " reads";
  EXPECT_EQ(buffer.read().seq, kLast);
}

}  // namespace
}  // namespace rigctl
