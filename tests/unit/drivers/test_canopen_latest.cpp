// The hand-over of the valve's spool actual value from the CAN I/O thread
// to the loop (drivers/canopen/canopen_latest.hpp): a writer preempted
// inside a store must not make the loop see "no value" (which faults the
// rig at once), only an older one, judged by its age.
#include <gtest/gtest.h>

#include "drivers/canopen/canopen_latest.hpp"

namespace rigctl {
namespace {

ValveActual actual(uint64_t count, int64_t rx_ns, double spool) {
  ValveActual a;
  a.count = count;
  a.rx_ns = rx_ns;
  a.status_word = 0x000F;
  a.spool = spool;
  return a;
}

TEST(LatestValveActual, ALoadGetsTheLastStoreWhole) {
  LatestValveActual latest;
  ValveActual a;
  ASSERT_TRUE(latest.load(a));
  EXPECT_EQ(a.count, 0U) << "nothing received yet";
  latest.store(actual(1, 1000, 0.25));
  latest.store(actual(2, 3000, 0.5));
  ASSERT_TRUE(latest.load(a));
  EXPECT_EQ(a.count, 2U);
  EXPECT_EQ(a.rx_ns, 3000);
  EXPECT_EQ(a.spool, 0.5);
  EXPECT_EQ(a.status_word, 0x000F);
}

TEST(LatestValveActual, WhileTheWriterIsInsideAStoreTheReaderKeepsItsPreviousCopy) {
  LatestValveActual latest;
  ValveActual kept;
  latest.store(actual(7, 5000, 0.3));
  EXPECT_EQ(load_or_keep(latest, kept).count, 7U);
  latest.begin_store();  // the I/O thread preempted here
  ValveActual a;
  EXPECT_FALSE(latest.load(a)) << "no consistent copy while a store is open";
  const ValveActual seen = load_or_keep(latest, kept);
  EXPECT_EQ(seen.count, 7U) << "the previous copy, not 'none received'";
  EXPECT_EQ(seen.rx_ns, 5000) << "with its own receive time, so its age shows";
  EXPECT_EQ(seen.spool, 0.3);
  latest.finish_store(actual(8, 7500, 0.4));
  EXPECT_EQ(load_or_keep(latest, kept).count, 8U);
  EXPECT_EQ(kept.spool, 0.4);
}

TEST(LatestValveActual, AFinishWithoutABeginIsAWholeStore) {
  LatestValveActual latest;
  latest.finish_store(actual(3, 900, 0.1));
  ValveActual a;
  ASSERT_TRUE(latest.load(a)) << "the counter must not stay odd";
  EXPECT_EQ(a.count, 3U);
  latest.store(actual(4, 1000, 0.2));
  ASSERT_TRUE(latest.load(a));
  EXPECT_EQ(a.count, 4U);
}

TEST(LatestValveActual, AReaderThatNeverHadACopyStillHasNone) {
  LatestValveActual latest;
  ValveActual kept;
  latest.begin_store();
  EXPECT_EQ(load_or_keep(latest, kept).count, 0U);
}

}  // namespace
}  // namespace rigctl
