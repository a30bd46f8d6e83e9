// MIMO drive iteration on a two-poster half car written for the tests
// (tests/support/two_poster_linear_rig.hpp, its dampers asymmetric: a
// nonlinearity the FRF does not hold): a target over both axles that a
// road made on this rig, reached by iterating the vector of drives from
// the measured matrix of FRFs and from the rig's transfer matrix (a
// model), against the same target iterated one channel at a time.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tools/identify/mimo_excitation.hpp"
#include "tools/identify/mimo_frf.hpp"
#include "tools/iterate/mimo_iteration.hpp"
#include "tools/iterate/spectrum.hpp"
#include "two_poster_linear_rig.hpp"
#include "two_poster_road.hpp"

namespace rigctl {
namespace {

using test::TwoPosterLinearRig;

constexpr double kPeriod = 0.0025;
// 10 s periods: 0.1 Hz lines. The body's pitch mode is lightly damped, and
// between lines 0.25 Hz apart the interpolated FRF missed it (the first
// drive's error stayed at 20-50 % with the rig's exact transfer matrix).
constexpr std::size_t kTicks = 4000;

// Seed 001's half car has a dynamic index a b m_s / I = 0.92: its centres
// of percussion lie almost over the axles, so a force at one axle hardly
// moves the body over the other, and a one-channel iteration does nearly as
// well on it (tried: both reach 0.3 % in six iterations). A body with twice
// that pitch inertia (dynamic index 0.46: a van loaded at its ends) couples
// the axles strongly; the tests use it, since that is where the MIMO update
// counts.
TwoPosterLinearRig coupled_rig() {
  TwoPosterLinearRig rig;
  rig.inertia = 2.0 * 2070.0;
  return rig;
}

TwoPosterLinearRig rig_with_effects() {
  TwoPosterLinearRig rig = coupled_rig();
  rig.rebound_factor = 1.4;  // dampers 40 % stiffer in rebound than in compression: not in any FRF
  rig.noise_m = 20e-6;
  return rig;
}

MimoFrf measured_frf(const TwoPosterLinearRig& rig) {
  std::vector<std::size_t> lines;
  for (std::size_t k = 5; k <= 200; ++k) lines.push_back(k);  // 0.5 .. 20 Hz
  const auto e = orthogonal_multisines(lines, kTicks, 2, 4, 0.003, 5);
  const auto played = played_records(e, 1);
  const auto drives = steady_periods(played, e, 1);
  const auto responses = steady_periods(rig.play(played, 3), e, 1);
  const WelchSettings welch{kTicks, kTicks, SpectralWindow::kRectangular, 1.0 / kPeriod};
  return estimate_mimo_frf({drives.begin(), drives.end()}, {responses.begin(), responses.end()}, welch, 0.5, 20.0, lines);
}

MimoFrf model_frf(const TwoPosterLinearRig& rig) {
  MimoFrf frf;
  frf.averages = 1000;  // a model: no estimation error
  for (double f = 0.1; f <= 20.0; f += 0.1) {
    frf.frequency_hz.push_back(f);
    frf.value.push_back(rig.frf(f));
    frf.multiple_coherence.push_back(Eigen::Vector2d::Ones());
    frf.partial_coherence.push_back(Eigen::Matrix2d::Ones());
    frf.input_condition.push_back(1.0);
  }
  return frf;
}

// What the body does over the axles on a road (tests/support/two_poster_road.hpp, 4 mm rms).
Records track_target(const TwoPosterLinearRig& rig) { return rig.play(test::two_poster_road(0.004, kPeriod), 99); }

bool each_better_than_the_last(const MimoIterationResult& r) {
  for (std::size_t it = 1; it < r.error.size(); ++it) {
    for (std::size_t j = 0; j < r.error[it].size(); ++j) {
      if (r.error[it][j] >= r.error[it - 1][j]) return false;
    }
  }
  return true;
}

MimoIterationResult iterate(const MimoFrf& frf, const TwoPosterLinearRig& rig, const Records& target, double tolerance) {
  MimoInverseSettings inverse_settings;
  inverse_settings.band_min_hz = 0.5;
  inverse_settings.band_max_hz = 20.0;
  const MimoDriveInverse inverse(frf, target.front().size(), kPeriod, inverse_settings);
  MimoIterationSettings s;
  s.tolerance = tolerance;
  unsigned seed = 100;
  return iterate_mimo(inverse, target, [&](const Records& d) { return rig.play(d, ++seed); }, s);
}

TEST(MimoIteration, ReachesAPitchCoupledTargetFromTheMeasuredFrf) {
  const auto rig = rig_with_effects();
  const auto target = track_target(rig);
  const auto result = iterate(measured_frf(rig), rig, target, 0.05);
  ASSERT_TRUE(result.converged) << "front " << result.error.back()[0] << ", rear " << result.error.back()[1];
  EXPECT_LE(result.error.size(), 6u);
  EXPECT_TRUE(each_better_than_the_last(result));
}

TEST(MimoIteration, ReachesItFromTheModelsTransferMatrix) {
  const auto rig = rig_with_effects();
  const auto target = track_target(rig);
  const auto result = iterate(model_frf(coupled_rig()), rig, target, 0.05);
  ASSERT_TRUE(result.converged) << "front " << result.error.back()[0] << ", rear " << result.error.back()[1];
  EXPECT_TRUE(each_better_than_the_last(result));
}

TEST(MimoIteration, OneChannelAtATimeStaysAtLeastTwiceAsFarAfterSixIterations) {
  const auto rig = rig_with_effects();
  const auto target = track_target(rig);
  const MimoFrf frf = measured_frf(rig);
  const auto mimo = iterate(frf, rig, target, 0.0);
  const auto siso = iterate(diagonal_only(frf), rig, target, 0.0);
  for (std::size_t it = 0; it < mimo.error.size(); ++it) {
    std::printf("iteration %zu: MIMO front %.4f rear %.4f, one channel at a time front %.4f rear %.4f\n", it + 1,
                mimo.error[it][0], mimo.error[it][1], siso.error[it][0], siso.error[it][1]);
  }
  ASSERT_EQ(mimo.error.size(), 6u);
  ASSERT_EQ(siso.error.size(), 6u);
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_GE(siso.error.back()[j], 2.0 * mimo.error.back()[j]) << "channel " << j << ": SISO " << siso.error.back()[j]
                                                                << ", MIMO " << mimo.error.back()[j];
  }
}

TEST(MimoIteration, WeightedLeastSquaresWithMoreResponsesThanDrives) {
  // Three responses (both axles and their mean) from two drives: the
  // inverse is a least-squares one and still converges on a reachable target.
  const auto rig = rig_with_effects();
  auto target = track_target(rig);
  MimoFrf frf = model_frf(coupled_rig());
  Eigen::MatrixXd t(3, 2);
  t << 1, 0, 0, 1, 0.5, 0.5;
  frf = transformed(frf, t);
  std::vector<double> mean(target[0].size());
  for (std::size_t i = 0; i < mean.size(); ++i) mean[i] = 0.5 * (target[0][i] + target[1][i]);
  target.push_back(mean);
  MimoInverseSettings inverse_settings;
  inverse_settings.band_min_hz = 0.5;
  inverse_settings.band_max_hz = 20.0;
  inverse_settings.weights = {1.0, 1.0, 2.0};
  const MimoDriveInverse inverse(frf, target.front().size(), kPeriod, inverse_settings);
  unsigned seed = 300;
  const auto result = iterate_mimo(inverse, target, [&](const Records& d) {
    auto y = rig.play(d, ++seed);
    std::vector<double> m(y[0].size());
    for (std::size_t i = 0; i < m.size(); ++i) m[i] = 0.5 * (y[0][i] + y[1][i]);
    y.push_back(m);
    return y;
  }, MimoIterationSettings{});
  EXPECT_TRUE(result.converged) << result.error.back()[0] << " " << result.error.back()[1] << " " << result.error.back()[2];
}

}  // namespace
}  // namespace rigctl

namespace rigctl {
namespace {

MimoFrf flat_frf(double coherence_above_5hz) {
  MimoFrf frf;
  frf.averages = 16;
  for (double f = 0.1; f <= 20.0; f += 0.1) {
    frf.frequency_hz.push_back(f);
    Eigen::Matrix2cd h;
    h << 1.0, 0.5, 0.5, 1.0;
    frf.value.push_back(h);
    frf.multiple_coherence.push_back(Eigen::Vector2d::Constant(f > 5.0 ? coherence_above_5hz : 1.0));
    frf.partial_coherence.push_back(Eigen::Matrix2d::Ones());
    frf.input_condition.push_back(1.0);
  }
  return frf;
}

TEST(MimoInverse, InvertsACoupledMatrixExactlyAndLeavesGatedLinesAlone) {
  const std::size_t n = 4000;
  MimoInverseSettings s;
  s.band_min_hz = 0.5;
  s.band_max_hz = 20.0;
  const MimoDriveInverse inverse(flat_frf(0.5), n, kPeriod, s);
  EXPECT_GT(inverse.report().lines_gated, 0u);
  // e = H d for d = (sin 2 Hz, 0) and (0, sin 8 Hz): the 2 Hz part comes
  // back as the drive that made it; the 8 Hz part is on gated lines.
  Records e(2, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double slow = std::sin(2.0 * std::numbers::pi * 2.0 * i * kPeriod);
    const double fast = std::sin(2.0 * std::numbers::pi * 8.0 * i * kPeriod);
    e[0][i] = slow + 0.5 * fast;
    e[1][i] = 0.5 * slow + fast;
  }
  const Eigen::MatrixXd gain = Eigen::MatrixXd::Ones(static_cast<Eigen::Index>(inverse.bands().size()), 2);
  const Records d = inverse.apply(e, gain);
  double first = 0.0, second = 0.0;
  for (std::size_t i = n / 4; i < 3 * n / 4; ++i) {
    first = std::max(first, std::abs(d[0][i] - std::sin(2.0 * std::numbers::pi * 2.0 * i * kPeriod)));
    second = std::max(second, std::abs(d[1][i]));
  }
  EXPECT_LT(first, 0.03);   // the zero padding's edge effects stay at the record's ends
  EXPECT_LT(second, 0.03);  // nothing at 8 Hz: those lines were not inverted
}

TEST(MimoInverse, RefusesWeightsAndTransformsOfTheWrongShape) {
  MimoInverseSettings s;
  s.weights = {1.0};
  EXPECT_THROW(MimoDriveInverse(flat_frf(1.0), 100, kPeriod, s), std::invalid_argument);
  EXPECT_THROW(transformed(flat_frf(1.0), Eigen::MatrixXd::Ones(2, 3)), std::invalid_argument);
}

}  // namespace
}  // namespace rigctl
