// Loop timing statistics from injected timestamps: the numbers the loop
// publishes must be what the timestamps say, whatever the machine does.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "rt/histogram.hpp"
#include "rt/timing_stats.hpp"

using namespace rigctl;

namespace {
constexpr int64_t kPeriod = 2'500'000;

int64_t exact_nearest_rank(std::vector<int64_t> v, double p) {
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::max(1.0, std::ceil(p * static_cast<double>(v.size()))));
  return v[rank - 1];
}
}  // namespace

TEST(Histogram, PercentilesMatchSortedDataWithinOneBin) {
  DurationHistogram h(1000, 5001);
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> dist(10.0, 0.8);  // ~22 us median, long tail like wake-up latency
  std::vector<int64_t> values;
  for (int i = 0; i < 20000; ++i) {
    const auto v = static_cast<int64_t>(dist(rng));
    values.push_back(v);
    h.record(v);
  }
  for (double p : {0.5, 0.9, 0.99, 0.999}) {
    const int64_t exact = exact_nearest_rank(values, p);
    const int64_t reported = h.percentile(p);
    EXPECT_GE(reported, exact) << "p=" << p;  // never optimistic
    EXPECT_LE(reported - exact, 1000) << "p=" << p;
  }
  const auto s = h.summary();
  EXPECT_EQ(s.count, 20000);
  EXPECT_EQ(s.min_ns, *std::min_element(values.begin(), values.end()));
  EXPECT_EQ(s.max_ns, *std::max_element(values.begin(), values.end()));
  double sum = 0;
  for (auto v : values) sum += static_cast<double>(v);
  EXPECT_NEAR(s.mean_ns, sum / 20000.0, 1e-6);
}

TEST(Histogram, ValuesBeyondRangeKeepExactMax) {
  DurationHistogram h(1000, 10);
  h.record(500);
  h.record(50'000'000);  // 50 ms: far beyond the last bin
  EXPECT_EQ(h.summary().max_ns, 50'000'000);
  EXPECT_EQ(h.percentile(1.0), 50'000'000);
  EXPECT_EQ(h.percentile(0.5), 1000);
}

TEST(TimingStats, LatencyAndComputeFromInjectedTimestamps) {
  TimingStats stats(kPeriod, OverrunPolicy::kSkip);
  int64_t deadline = 0;
  // 100 ticks: latency 10..109 us, compute 200 us each.
  for (int i = 0; i < 100; ++i) {
    const int64_t wake = deadline + (10 + i) * 1000;
    stats.on_wake(deadline, wake);
    deadline = stats.on_done(deadline, wake, wake + 200'000);
  }
  const auto s = stats.summary();
  EXPECT_EQ(s.ticks, 100);
  EXPECT_EQ(s.overruns, 0);
  EXPECT_EQ(s.wakeup_latency.min_ns, 10'000);
  EXPECT_EQ(s.wakeup_latency.max_ns, 109'000);
  EXPECT_NEAR(s.wakeup_latency.mean_ns, 59'500, 1e-6);
  EXPECT_EQ(s.wakeup_latency.p50_ns, 60'000);  // 50th of 10..109 us is 59 us, in bin [59, 60) us
  EXPECT_EQ(s.wakeup_latency.p99_ns, 109'000);
  EXPECT_EQ(s.compute.min_ns, 200'000);
  EXPECT_EQ(s.compute.max_ns, 200'000);
  EXPECT_EQ(deadline, 100 * kPeriod);  // no overrun: the grid is kept exactly
}

TEST(TimingStats, SkipPolicyDropsMissedPeriodsAndKeepsPhase) {
  TimingStats stats(kPeriod, OverrunPolicy::kSkip);
  // A tick starting on time that takes 6 ms ends 3.5 ms past the next deadline:
  // deadlines at 2.5 and 5.0 ms are missed, the next tick waits for 7.5 ms.
  stats.on_wake(0, 0);
  const int64_t next = stats.on_done(0, 0, 6'000'000);
  EXPECT_EQ(next, 3 * kPeriod);
  auto s = stats.summary();
  EXPECT_EQ(s.overruns, 1);
  EXPECT_EQ(s.missed_ticks, 2);
  // A tick ending exactly on the next deadline is not an overrun.
  stats.on_wake(next, next);
  EXPECT_EQ(stats.on_done(next, next, next + kPeriod), next + kPeriod);
  EXPECT_EQ(stats.summary().overruns, 1);
}

TEST(TimingStats, CatchUpPolicyKeepsEveryDeadline) {
  TimingStats stats(kPeriod, OverrunPolicy::kCatchUp);
  stats.on_wake(0, 0);
  EXPECT_EQ(stats.on_done(0, 0, 6'000'000), kPeriod);  // runs the next tick at once, late
  const auto s = stats.summary();
  EXPECT_EQ(s.overruns, 1);
  EXPECT_EQ(s.missed_ticks, 0);
}

TEST(TimingStats, PolicyNamesRoundTrip) {
  EXPECT_EQ(overrun_policy_from_string("skip"), OverrunPolicy::kSkip);
  EXPECT_EQ(overrun_policy_from_string("catch_up"), OverrunPolicy::kCatchUp);
  EXPECT_EQ(to_string(OverrunPolicy::kCatchUp), "catch_up");
  EXPECT_THROW(overrun_policy_from_string("ignore"), std::invalid_argument);
}
