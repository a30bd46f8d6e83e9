// The change detector of rig health (tools/health/cusum.hpp) against
// numbers it did not make: Siegmund's approximation of the tabular CUSUM's
// in-control run length, the change point of a step this test placed, and
// the size of the step.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tools/health/cusum.hpp"

using namespace rigctl::health;

namespace {

// Siegmund (1985): one side's mean run length for a standardised shift
// delta, ARL = (exp(-2 D b) + 2 D b - 1) / (2 D^2), D = delta - k, b = h + 1.166.
double siegmund_arl(double delta, double k, double h) {
  const double d = delta - k, b = h + 1.166;
  return (std::exp(-2.0 * d * b) + 2.0 * d * b - 1.0) / (2.0 * d * d);
}

}  // namespace

TEST(Cusum, InControlRunLengthMatchesSiegmund) {
  // Two-sided chart: alarms of either side, 1/ARL = 1/ARL+ + 1/ARL-.
  const CusumSettings s{0.5, 4.0};  // h = 4: runs short enough to average many
  const double expected = siegmund_arl(0.0, s.k, s.h) / 2.0;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> z(0.0, 1.0);
  double total = 0.0;
  int runs = 0;
  for (; runs < 400; ++runs) {
    std::vector<CusumPoint> pts;
    CusumTrace t;
    // Grow the record until the first alarm (each record is fresh noise).
    while (t.alarms.empty()) {
      for (int i = 0; i < 200; ++i) pts.push_back({z(rng), 1.0});
      t = run_cusum(pts, 0.0, s);
    }
    total += static_cast<double>(t.alarms.front().raised_at + 1);
  }
  const double mean = total / runs;
  // The run length is about exponential: the mean of 400 has a 5 % standard error.
  EXPECT_NEAR(mean, expected, 0.2 * expected) << "Siegmund " << expected;
}

TEST(Cusum, AStepIsFoundWithItsStartSizeAndSign) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<CusumPoint> pts;
  for (int i = 0; i < 60; ++i) pts.push_back({10.0 + noise(rng) - (i >= 40 ? 0.1 : 0.0), 0.02});  // -5 sd from 40 on
  const auto t = run_cusum(pts, 10.0, {});
  ASSERT_EQ(t.alarms.size(), 1u);
  const auto& a = t.alarms[0];
  EXPECT_EQ(a.direction, -1);
  EXPECT_GE(a.raised_at, 40u);
  EXPECT_LE(a.raised_at, 42u);  // a 5 sd step crosses h = 5 within two points
  EXPECT_EQ(a.since, 40u);  // the likeliest start, though noise may have lifted the sum earlier
  EXPECT_NEAR(a.mean_shift, -0.1, 0.03);
  EXPECT_NEAR(a.mean_shift_sigma, -5.0, 1.5);
  ASSERT_EQ(t.upper.size(), pts.size());
  EXPECT_GT(t.lower.back(), 5.0);
}

TEST(Cusum, OneAlarmPerExcursionAndReArmedAfterIt) {
  std::vector<CusumPoint> pts;
  for (int i = 0; i < 20; ++i) pts.push_back({0.0, 1.0});
  for (int i = 0; i < 20; ++i) pts.push_back({3.0, 1.0});   // up: one alarm, not twenty
  for (int i = 0; i < 40; ++i) pts.push_back({-1.0, 1.0});  // back down past zero: the upper sum empties
  for (int i = 0; i < 20; ++i) pts.push_back({3.0, 1.0});   // up again: a second alarm
  const auto t = run_cusum(pts, 0.0, {});
  int up = 0, down = 0;
  for (const auto& a : t.alarms) (a.direction > 0 ? up : down)++;
  EXPECT_EQ(up, 2);
  EXPECT_EQ(down, 1);  // -1 sd for 40 points: (1 - 0.5) x 40 = 20 > h
}
