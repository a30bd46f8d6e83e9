// Per-step tick timing from injected timestamps: each step gets the time
// since the previous stamp, the run keeps each step's maximum and mean and
// the breakdown of the slowest tick, and through TimingStats the steps add
// up to the compute time the loop reports.
#include "rt/tick_stages.hpp"

#include <gtest/gtest.h>

#include "rt/timing_stats.hpp"

using namespace rigctl;

namespace {

constexpr auto kRead = static_cast<std::size_t>(TickStage::kRead);
constexpr auto kCheck = static_cast<std::size_t>(TickStage::kCheck);
constexpr auto kControl = static_cast<std::size_t>(TickStage::kControl);
constexpr auto kWrite = static_cast<std::size_t>(TickStage::kWrite);
constexpr auto kHandOff = static_cast<std::size_t>(TickStage::kHandOff);

// One tick from `start`: read, check, control, write and hand-off taking the given ns.
void tick(TickStageTimes& t, int64_t n, int64_t start, int64_t read, int64_t check, int64_t control, int64_t write,
          int64_t hand_off) {
  t.begin(n, start);
  int64_t at = start + read;
  t.end(TickStage::kRead, at);
  t.end(TickStage::kCheck, at += check);
  t.end(TickStage::kControl, at += control);
  t.end(TickStage::kWrite, at += write);
  t.end(TickStage::kHandOff, at += hand_off);
  t.finish();
}

TEST(TickStages, EachStepGetsTheTimeSinceThePreviousStamp) {
  TickStageTimes t;
  tick(t, 0, 1'000'000, 500, 200, 300, 100, 900);
  const TickStageSummary s = t.summary();
  EXPECT_EQ(s.ticks, 1);
  EXPECT_EQ(s.max_ns[kRead], 500);
  EXPECT_EQ(s.max_ns[kCheck], 200);
  EXPECT_EQ(s.max_ns[kControl], 300);
  EXPECT_EQ(s.max_ns[kWrite], 100);
  EXPECT_EQ(s.max_ns[kHandOff], 900);
  // Steps not stamped (commands, demand) took no time in this tick.
  EXPECT_EQ(s.max_ns[static_cast<std::size_t>(TickStage::kCommands)], 0);
  EXPECT_EQ(s.max_ns[static_cast<std::size_t>(TickStage::kDemand)], 0);
}

TEST(TickStages, MaximaMeansAndTheSlowestTickAreKeptApart) {
  TickStageTimes t;
  tick(t, 0, 0, 100, 100, 100, 100, 100);           // total 500
  tick(t, 1, 2'500'000, 4000, 10, 10, 10, 10);      // total 4040: the slowest, by its read
  tick(t, 2, 5'000'000, 100, 100, 100, 100, 3000);  // total 3400: the longest hand-off
  const TickStageSummary s = t.summary();
  EXPECT_EQ(s.ticks, 3);
  EXPECT_EQ(s.max_ns[kRead], 4000);
  EXPECT_EQ(s.max_ns[kHandOff], 3000);
  EXPECT_DOUBLE_EQ(s.mean_ns[kRead], (100 + 4000 + 100) / 3.0);
  EXPECT_EQ(s.slowest_tick, 1);
  EXPECT_EQ(s.slowest_tick_ns[kRead], 4000);
  EXPECT_EQ(s.slowest_tick_ns[kHandOff], 10);  // that tick's own hand-off, not the run's longest
}

TEST(TickStages, AStepStampedTwiceInATickAddsUp) {
  TickStageTimes t;
  t.begin(0, 0);
  t.end(TickStage::kCheck, 100);
  t.end(TickStage::kCheck, 350);
  t.finish();
  EXPECT_EQ(t.summary().max_ns[kCheck], 350);
}

TEST(TickStages, NamesFollowTheTickOrder) {
  EXPECT_EQ(to_string(TickStage::kRead), "read");
  EXPECT_EQ(to_string(TickStage::kHandOff), "hand_off");
  EXPECT_EQ(static_cast<std::size_t>(TickStage::kHandOff) + 1, kTickStageCount);
}

TEST(TickStages, ThroughTimingStatsTheStepsAddUpToTheCompute) {
  constexpr int64_t kPeriod = 2'500'000;
  TimingStats stats(kPeriod, OverrunPolicy::kSkip);
  int64_t deadline = 0;
  const int64_t reads[] = {3000, 250'000, 9000};
  for (int64_t n = 0; n < 3; ++n) {
    const int64_t wake = deadline + 40'000;
    stats.on_wake(deadline, wake);
    stats.on_stage(TickStage::kRead, wake + reads[n]);
    stats.on_stage(TickStage::kHandOff, wake + reads[n] + 5000);
    deadline = stats.on_done(deadline, wake, wake + reads[n] + 5000);
  }
  const TimingSummary s = stats.summary();
  EXPECT_EQ(s.stages.ticks, 3);
  EXPECT_EQ(s.stages.slowest_tick, 1);
  EXPECT_EQ(s.stages.slowest_tick_ns[kRead] + s.stages.slowest_tick_ns[kHandOff], s.compute.max_ns);
  EXPECT_EQ(s.stages.max_ns[kRead], 250'000);
}

}  // namespace
