// The regularised, coherence-gated inverse on whole records and the
// frequency-domain tools under it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "tools/iterate/drive_inverse.hpp"
#include "tools/iterate/match_metrics.hpp"
#include "tools/iterate/spectrum.hpp"

namespace rigctl {
namespace {

constexpr double kDt = 0.0025;

// A known rig: gain 0.5 and a 10 ms delay (a non-minimum-phase-free but
// causal response the inverse must undo with a 10 ms advance).
DriveFrf delayed_half(double coherence = 1.0) {
  DriveFrf d;
  for (double f = 0.25; f <= 40.0; f += 0.25) {
    d.frequency_hz.push_back(f);
    d.value.push_back(0.5 * std::polar(1.0, -2 * std::numbers::pi * f * 0.010));
    d.coherence.push_back(coherence);
  }
  return d;
}

std::vector<double> band_noise(std::size_t n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> x(n);
  for (double& v : x) v = g(rng);
  return band_limited(x, kDt, lo, hi);
}

TEST(DriveInverse, UndoesAKnownGainAndDelayInTheBand) {
  const std::size_t n = 8000;
  const auto x = band_noise(n, 0.5, 30.0, 1);
  std::vector<double> y(n, 0.0);  // the rig's response: half, 4 ticks late
  for (std::size_t i = 4; i < n; ++i) y[i] = 0.5 * x[i - 4];
  InverseSettings s;
  s.regularisation = 0.01;
  const DriveInverse inv(delayed_half(), n, kDt, s);
  const auto back = inv.apply(y, std::vector<double>(inv.bands().size(), 1.0));
  // Away from the ends (the record is not periodic), x comes back.
  const std::vector<double> mid_x(x.begin() + 400, x.end() - 400), mid_b(back.begin() + 400, back.end() - 400);
  const auto m = match_metrics(mid_x, mid_b, kDt, 0.5, 30.0);
  EXPECT_LT(m.rel_rms_percent, 1.0);
  EXPECT_GT(m.trac, 0.999);
}

TEST(DriveInverse, GainPerBandScalesTheCorrectionThere) {
  const std::size_t n = 4000;
  const auto x = band_noise(n, 0.5, 30.0, 2);
  const DriveInverse inv(delayed_half(), n, kDt, InverseSettings{});
  const auto full = inv.apply(x, std::vector<double>(inv.bands().size(), 1.0));
  const auto half = inv.apply(x, std::vector<double>(inv.bands().size(), 0.5));
  for (std::size_t i = 0; i < n; i += 97) ASSERT_NEAR(half[i], 0.5 * full[i], 1e-12);
  const auto e = inv.band_energy(x);
  ASSERT_EQ(e.size(), inv.bands().size());
  EXPECT_GT(e.back(), 0.0);
}

TEST(DriveInverse, LinesBelowTheCoherenceGateAreNotInverted) {
  const std::size_t n = 4000;
  const auto x = band_noise(n, 0.5, 30.0, 3);
  const DriveInverse gated(delayed_half(0.5), n, kDt, InverseSettings{});
  EXPECT_GT(gated.lines_gated(), 0u);
  const auto out = gated.apply(x, std::vector<double>(gated.bands().size(), 1.0));
  for (double v : out) ASSERT_EQ(v, 0.0);
}

TEST(DriveInverse, RegularisationBoundsTheGainWhereTheRigHardlyResponds) {
  DriveFrf d = delayed_half();
  for (std::size_t i = 0; i < d.frequency_hz.size(); ++i) {
    if (d.frequency_hz[i] > 10.0) d.value[i] *= 1e-4;  // a rig that passes nothing above 10 Hz
  }
  const std::size_t n = 4000;
  const auto x = band_noise(n, 12.0, 30.0, 4);
  InverseSettings s;  // eps = 0.05 max|H|: |H^-1| <= 1 / (2 eps) = 10 / 0.5 = 20
  const DriveInverse inv(d, n, kDt, s);
  const auto out = inv.apply(x, std::vector<double>(inv.bands().size(), 1.0));
  double xx = 0, oo = 0;
  for (std::size_t i = 0; i < n; ++i) {
    xx += x[i] * x[i];
    oo += out[i] * out[i];
  }
  EXPECT_LT(std::sqrt(oo / xx), 1.0);  // without regularisation it would be 2e4
}

TEST(DriveInverse, InterpolatesTheFrfBetweenLines) {
  DriveFrf d;
  d.frequency_hz = {1.0, 3.0};
  d.value = {{1.0, 0.0}, {0.0, 2.0}};
  d.coherence = {1.0, 0.6};
  EXPECT_EQ(d.at(2.0), std::complex<double>(0.5, 1.0));
  EXPECT_EQ(d.at(0.1), std::complex<double>(1.0, 0.0));
  EXPECT_EQ(d.at(9.0), std::complex<double>(0.0, 2.0));
  EXPECT_DOUBLE_EQ(d.coherence_at(2.0), 0.8);
}

TEST(MatchMetrics, RelativeErrorCorrelationAndPeak) {
  const auto t = band_noise(4000, 0.5, 30.0, 5);
  std::vector<double> r(t);
  for (double& v : r) v *= 1.1;
  const auto m = match_metrics(t, r, kDt, 0.5, 30.0);
  EXPECT_NEAR(m.rel_rms_percent, 10.0, 1e-6);
  EXPECT_NEAR(m.trac, 1.0, 1e-12);
  double peak = 0;
  const auto tb = band_passed(t, kDt, 0.5, 30.0);
  for (double v : tb) peak = std::max(peak, 0.1 * std::abs(v));
  EXPECT_NEAR(m.peak_error, peak, 1e-9);
  const auto other = band_noise(4000, 0.5, 30.0, 6);
  EXPECT_LT(match_metrics(t, other, kDt, 0.5, 30.0).trac, 0.01);
  // An offset (below the band) does not count.
  std::vector<double> shifted(t);
  for (double& v : shifted) v += 0.08;
  EXPECT_LT(match_metrics(t, shifted, kDt, 0.5, 30.0).rel_rms_percent, 1e-6);
}

// The error that counts is the one over the test part: an error outside it
// shows in the whole record's figure only.
TEST(MatchMetrics, TheWindowsErrorAndTheWholeRecordsBesideIt) {
  const auto t = band_noise(4000, 0.5, 30.0, 5);
  std::vector<double> r(t);
  for (std::size_t i = 3000; i < 4000; ++i) r[i] *= 1.5;  // wrong in the last 2.5 s only
  const TestWindow first{0, 2000, "--window"};
  const auto m = match_metrics(t, r, kDt, 0.5, 30.0, first);
  EXPECT_LT(m.rel_rms_percent, 3.0);  // the band-pass spreads a little of the error's sudden start (1.8 %)
  EXPECT_GT(m.whole_rel_rms_percent, 20.0);
  const TestWindow last{3200, 3800, "--window"};
  EXPECT_NEAR(match_metrics(t, r, kDt, 0.5, 30.0, last).rel_rms_percent, 50.0, 5.0);
}

}  // namespace
}  // namespace rigctl
