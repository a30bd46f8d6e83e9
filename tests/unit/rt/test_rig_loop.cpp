// The loop's scheduling, timing statistics and ways out, with a clock and a
// driver whose timing the test scripts.
#include <gtest/gtest.h>

#include <vector>

#include "rt/control/pi_controller.hpp"
#include "rt/loop/rig_loop.hpp"

using namespace rigctl;

namespace {

constexpr int64_t kPeriod = 2'500'000;

// Time moves only when the loop sleeps (to the deadline plus a scripted
// wake-up latency) and when the driver reads (by a scripted compute time).
class ScriptedClock final : public LoopClock {
 public:
  int64_t now_ns() noexcept override { return now; }
  void sleep_until(int64_t deadline) noexcept override {
    deadlines.push_back(deadline);
    if (deadline > now) now = deadline;
    now += latency.empty() ? 0 : latency[(deadlines.size() - 1) % latency.size()];
  }
  int64_t now = 1'000'000'000;
  std::vector<int64_t> latency;
  std::vector<int64_t> deadlines;
};

class ScriptedDriver final : public Driver {
 public:
  explicit ScriptedDriver(ScriptedClock& clock) : clock_(clock) {
    layout_.inputs = {{"x", "m"}};
    layout_.outputs = {{"u", "1"}};
  }
  const ChannelLayout& layout() const override { return layout_; }
  void start() override {}
  bool read(Sample& out) override {
    const std::size_t k = reads++;
    clock_.now += compute.empty() ? 0 : compute[k % compute.size()];
    out.t_ns = static_cast<int64_t>(k) * kPeriod;
    out.value[0] = k < values.size() ? values[k] : 0.0;
    return !(fail_at >= 0 && static_cast<int64_t>(k) == fail_at);
  }
  void write(const Command& c) override { written.push_back(c.value[0]); }
  void make_safe() noexcept override { ++safe_calls; }
  void stop() override {}

  std::vector<int64_t> compute;
  std::vector<double> values;
  std::vector<double> written;
  int64_t fail_at = -1;
  std::size_t reads = 0;
  int safe_calls = 0;

 private:
  ScriptedClock& clock_;
  ChannelLayout layout_;
};

class CollectingSink final : public TelemetrySink {
 public:
  bool push(const TelemetryRecord& r) noexcept override {
    if (refuse) return false;
    records.push_back(r);
    return true;
  }
  std::vector<TelemetryRecord> records;
  bool refuse = false;
};

struct Fixture {
  ScriptedClock clock;
  ScriptedDriver driver{clock};
  PiController pi{PiConfig{}};
  // A demand at rest where the rod is: the controlled stop at max_ticks
  // settles at once, so a run of N ticks is N ticks (these tests are about
  // scheduling; tests/unit/rt/test_rig_loop_safety.cpp ramps).
  FilteredProfile profile{std::make_unique<RampStepsProfile>(LeadIn{0.0, 0.0, 0.0, 1.0}, std::vector<double>{0.0}, 100.0),
                          0.0, 0.0025};
  CollectingSink sink;
  std::atomic<bool> stop{false};

  // What rig assembly makes of `limits: {x: [-1, 1]}`: the input's
  // plausibility, then its range, both interlocks.
  static LimitDetectors detectors() {
    DetectorSpec invalid;
    invalid.name = "invalid.x";
    invalid.kind = DetectorKind::kInvalid;
    invalid.channel = 0;
    DetectorSpec range;
    range.name = "limits.x";
    range.kind = DetectorKind::kRange;
    range.channel = 0;
    range.min = -1.0;
    range.max = 1.0;
    return LimitDetectors({invalid, range}, 1, 0, 0.0025);
  }

  LoopResult run(int64_t ticks, OverrunPolicy policy = OverrunPolicy::kSkip, int64_t timing_every = 10) {
    LoopOptions o;
    o.period_ns = kPeriod;
    o.overrun_policy = policy;
    o.max_ticks = ticks;
    o.timing_every_ticks = timing_every;
    SafetyOptions s;  // the automatic sequence of `rigctl run`, the state machine's default rates
    s.feedback_input = 0;
    RigLoop loop(driver, pi, profile, detectors(), sink, clock, o, s);
    return loop.run(stop);
  }
};

}  // namespace

TEST(RigLoop, PublishesTimingComputedFromTheTimestampsItSaw) {
  Fixture f;
  for (int i = 0; i < 100; ++i) f.clock.latency.push_back((10 + i) * 1000);  // 10..109 us
  f.driver.compute = {200'000};                                            // 200 us per tick
  const auto result = f.run(100);
  ASSERT_EQ(result.ticks, 100);
  const auto& t = result.timing;
  EXPECT_EQ(t.ticks, 100);
  EXPECT_EQ(t.overruns, 0);
  EXPECT_EQ(t.wakeup_latency.min_ns, 10'000);
  EXPECT_EQ(t.wakeup_latency.max_ns, 109'000);
  EXPECT_NEAR(t.wakeup_latency.mean_ns, 59'500.0, 1e-6);
  EXPECT_EQ(t.compute.min_ns, 200'000);
  EXPECT_EQ(t.compute.max_ns, 200'000);
  // Absolute deadlines on an exact 2.5 ms grid: latency never accumulates.
  for (std::size_t k = 1; k < f.clock.deadlines.size(); ++k) {
    ASSERT_EQ(f.clock.deadlines[k] - f.clock.deadlines[k - 1], kPeriod) << k;
  }
  // Timing goes out every 10 ticks and on the closing record.
  int with_timing = 0;
  for (const auto& r : f.sink.records) with_timing += r.has_timing;
  EXPECT_EQ(with_timing, 11);
  EXPECT_EQ(f.sink.records.back().timing.wakeup_latency.max_ns, 109'000);
}

TEST(RigLoop, OverrunSkipsToTheNextGridPointAndIsCounted) {
  Fixture f;
  f.driver.compute = {100'000, 100'000, 6'000'000, 100'000, 100'000, 100'000};
  const auto result = f.run(6);
  EXPECT_EQ(result.timing.overruns, 1);
  EXPECT_EQ(result.timing.missed_ticks, 2);
  const int64_t t0 = f.clock.deadlines[0];
  // Tick 2 ran from 5.0 ms to 11.0 ms: deadlines 7.5 and 10.0 ms are skipped.
  EXPECT_EQ(f.clock.deadlines[3] - t0, 5 * kPeriod);
  EXPECT_EQ(f.clock.deadlines[4] - t0, 6 * kPeriod);
}

TEST(RigLoop, CatchUpRunsLateTicksBackToBack) {
  Fixture f;
  f.driver.compute = {100'000, 100'000, 6'000'000, 100'000, 100'000, 100'000};
  const auto result = f.run(6, OverrunPolicy::kCatchUp);
  // Tick 2 ends at 11.0 ms, past 7.5; tick 3 (due 7.5) ends at 11.1, past
  // 10.0: both are overruns. Tick 4 (due 10.0) ends at 11.2, before 12.5.
  EXPECT_EQ(result.timing.overruns, 2);
  EXPECT_EQ(result.timing.missed_ticks, 0);
  const int64_t t0 = f.clock.deadlines[0];
  EXPECT_EQ(f.clock.deadlines[3] - t0, 3 * kPeriod);
  // Tick 3 started late, at the end of tick 2 (11.0 ms): latency 3.5 ms.
  EXPECT_EQ(result.timing.wakeup_latency.max_ns, 3'500'000);
}

TEST(RigLoop, EndsNormallyWithASafeDriverAndAClosingRecord) {
  Fixture f;
  const auto result = f.run(20);
  EXPECT_EQ(result.final_state, RigState::kStopped);
  EXPECT_EQ(result.end_event.code, EventCode::kProfileFinished);
  EXPECT_EQ(f.driver.safe_calls, 1);
  ASSERT_EQ(f.sink.records.size(), 21u);
  EXPECT_EQ(f.sink.records.front().event.code, EventCode::kRunStarted);
  EXPECT_FALSE(f.sink.records.back().has_sample);
  EXPECT_EQ(f.sink.records.back().state, RigState::kStopped);
  for (int k = 0; k < 20; ++k) EXPECT_EQ(f.sink.records[static_cast<std::size_t>(k)].tick, k);
}

TEST(RigLoop, LimitTripMakesSafeBeforeWritingAndNamesTheChannel) {
  Fixture f;
  f.driver.values = {0.0, 0.0, 0.0, 1.5, 0.0};
  const auto result = f.run(10);
  EXPECT_EQ(result.final_state, RigState::kFaulted);
  EXPECT_EQ(result.end_event.code, EventCode::kLimitTripped);
  EXPECT_EQ(result.end_event.channel, 0);
  EXPECT_DOUBLE_EQ(result.end_event.value, 1.5);
  EXPECT_EQ(f.driver.written.size(), 3u) << "no command written on the faulted tick";
  EXPECT_GE(f.driver.safe_calls, 1);
  EXPECT_EQ(f.sink.records.back().state, RigState::kFaulted);
  EXPECT_EQ(f.sink.records.back().event.code, EventCode::kLimitTripped);
}

TEST(RigLoop, NotANumberIsAnInvalidInput) {
  Fixture f;
  f.driver.values = {0.0, std::nan("")};
  const auto result = f.run(10);
  EXPECT_EQ(result.end_event.code, EventCode::kInputInvalid);
  EXPECT_EQ(f.driver.written.size(), 1u);
}

TEST(RigLoop, DriverReadFailureFaults) {
  Fixture f;
  f.driver.fail_at = 4;
  const auto result = f.run(10);
  EXPECT_EQ(result.final_state, RigState::kFaulted);
  EXPECT_EQ(result.end_event.code, EventCode::kDriverReadFailed);
  EXPECT_GE(f.driver.safe_calls, 1);
}

TEST(RigLoop, StopRequestEndsTheRunCleanly) {
  Fixture f;
  f.stop = true;
  const auto result = f.run(10);
  EXPECT_EQ(result.ticks, 0);
  EXPECT_EQ(result.end_event.code, EventCode::kStopRequested);
  EXPECT_EQ(result.final_state, RigState::kStopped);
  EXPECT_EQ(f.driver.safe_calls, 1);
}

TEST(RigLoop, AFullTelemetryQueueDropsAndCountsButNeverStallsTheLoop) {
  Fixture f;
  f.sink.refuse = true;
  const auto result = f.run(50);
  EXPECT_EQ(result.ticks, 50);
  EXPECT_EQ(result.dropped_records, 51);
}
