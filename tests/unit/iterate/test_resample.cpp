// Targets at other rates: resampled through an anti-aliasing low-pass.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tools/iterate/resample.hpp"

namespace rigctl {
namespace {

std::vector<double> tone(double f_hz, double dt, double seconds, double offset = 0.0) {
  std::vector<double> x;
  for (std::size_t i = 0; i < static_cast<std::size_t>(std::llround(seconds / dt)); ++i) {
    x.push_back(offset + std::sin(2 * std::numbers::pi * f_hz * static_cast<double>(i) * dt));
  }
  return x;
}

double peak_between(const std::vector<double>& x, std::size_t from, std::size_t to, double offset = 0.0) {
  double p = 0.0;
  for (std::size_t i = from; i < to; ++i) p = std::max(p, std::abs(x[i] - offset));
  return p;
}

TEST(Resample, A512HzRecordLandsOn400HzWithItsContentKept) {
  const auto x = tone(7.0, 1.0 / 512, 4.0);
  const auto y = resample(x, 1.0 / 512, 0.0025);
  ASSERT_EQ(y.size(), static_cast<std::size_t>(std::floor(2047.0 / 512 / 0.0025 + 1e-9)) + 1);
  double worst = 0.0;
  for (std::size_t j = 200; j + 200 < y.size(); ++j) {
    worst = std::max(worst, std::abs(y[j] - std::sin(2 * std::numbers::pi * 7.0 * static_cast<double>(j) * 0.0025)));
  }
  EXPECT_LT(worst, 1e-3);
}

TEST(Resample, ContentAboveTheNewNyquistIsRemovedNotFolded) {
  // 300 Hz at 1 kHz has no place at 400 Hz: sampled as it is it would fold to 100 Hz.
  const auto y = resample(tone(300.0, 0.001, 2.0), 0.001, 0.0025);
  EXPECT_LT(peak_between(y, 100, y.size() - 100), 0.02);
  // 100 Hz, below 90 % of the new Nyquist frequency (180 Hz), stays.
  const auto z = resample(tone(100.0, 0.001, 2.0), 0.001, 0.0025);
  EXPECT_NEAR(peak_between(z, 100, z.size() - 100), 1.0, 0.02);
}

TEST(Resample, AHeldValueStaysExactlyThatValue) {
  const std::vector<double> home(1000, 0.0), mid(1000, 0.08);
  for (double v : resample(home, 0.001, 0.0025)) EXPECT_EQ(v, 0.0);
  for (double v : resample(mid, 1.0 / 512, 0.0025)) EXPECT_NEAR(v, 0.08, 1e-15);
  const std::vector<double> same{1.0, 2.0, 3.0};
  EXPECT_EQ(resample(same, 0.0025, 0.0025), same);
}

}  // namespace
}  // namespace rigctl
