// The matrix of frequency responses of a rig with two drives, measured with
// orthogonal multisines on a two-poster half car written for the tests
// (tests/support/two_poster_linear_rig.hpp), against that rig's own
// transfer matrix; and what correlated drives do to the estimate.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "tools/identify/mimo_excitation.hpp"
#include "tools/identify/mimo_frf.hpp"
#include "two_poster_linear_rig.hpp"

namespace rigctl {
namespace {

using test::TwoPosterLinearRig;

constexpr double kPeriod = 0.0025;
constexpr std::size_t kTicks = 1600;  // 4 s per period: 0.25 Hz lines

std::vector<std::size_t> lines_between(double low_hz, double high_hz) {
  std::vector<std::size_t> lines;
  for (std::size_t k = 1; k < kTicks / 2; ++k) {
    const double f = static_cast<double>(k) / (kTicks * kPeriod);
    if (f >= low_hz && f <= high_hz) lines.push_back(k);
  }
  return lines;
}

std::vector<std::span<const double>> spans(const std::vector<std::vector<double>>& x) {
  return {x.begin(), x.end()};
}

MimoFrf measure(const TwoPosterLinearRig& rig, std::size_t realisations) {
  const auto lines = lines_between(0.5, 20.0);
  const auto e = orthogonal_multisines(lines, kTicks, 2, realisations, 0.003, 11);
  const auto played = played_records(e, 1);
  const auto drives = steady_periods(played, e, 1);
  const auto responses = steady_periods(rig.play(played), e, 1);
  const WelchSettings welch{kTicks, kTicks, SpectralWindow::kRectangular, 1.0 / kPeriod};
  return estimate_mimo_frf(spans(drives), spans(responses), welch, 0.5, 20.0, lines);
}

TEST(MimoFrf, MatchesTheRigsTransferMatrixOnEveryEntry) {
  TwoPosterLinearRig rig;
  rig.noise_m = 20e-6;
  const MimoFrf frf = measure(rig, 16);
  ASSERT_EQ(frf.value.front().rows(), 2);
  ASSERT_EQ(frf.value.front().cols(), 2);
  int compared = 0;
  for (std::size_t k = 0; k < frf.frequency_hz.size(); ++k) {
    const Eigen::Matrix2cd truth = rig.frf(frf.frequency_hz[k]);
    for (int j = 0; j < 2; ++j) {
      const double g = frf.multiple_coherence[k](j);
      if (g < 0.9) continue;
      // The H1 estimate's random error at this coherence over the averages
      // (Bendat and Piersol 9.3), four of them allowed, and 1 % for the
      // zero-order hold's approximation; judged against the row's largest
      // entry (an entry far below it is swamped by the other drive's noise).
      const double relative = 0.01 + 4.0 * std::sqrt((1.0 - g) / (2.0 * frf.averages * g));
      for (int m = 0; m < 2; ++m) {
        const double scale = truth.row(j).cwiseAbs().maxCoeff();
        EXPECT_LT(std::abs(frf.value[k](j, m) - truth(j, m)), relative * scale)
            << "H(" << j << "," << m << ") at " << frf.frequency_hz[k] << " Hz";
        ++compared;
      }
    }
    EXPECT_LT(frf.input_condition[k], 1.5) << "orthogonal multisines leave S_xx diagonal";
  }
  EXPECT_GT(compared, 200);
}

TEST(MimoFrf, TheFrontPostMovesTheRearOfTheBody) {
  // The coupling the MIMO iteration exists for: near the body's pitch and
  // heave modes the front drive's effect on the rear is of the size of the
  // rear drive's own.
  TwoPosterLinearRig rig;
  double largest_ratio = 0.0;
  for (double f = 0.5; f <= 3.0; f += 0.05) {
    const Eigen::Matrix2cd h = rig.frf(f);
    largest_ratio = std::max(largest_ratio, std::abs(h(1, 0)) / std::abs(h(1, 1)));
  }
  EXPECT_GT(largest_ratio, 0.5);
}

TEST(MimoFrf, CorrelatedDrivesShowAsALowPartialCoherence) {
  // Drive 2 mostly follows drive 1 (a one-channel tool's "same road, rear
  // delayed" with an independent part 50 dB below): the multiple coherence stays
  // high (the responses are still explained by the drives together) but
  // the partial coherences, what each drive explains alone, fall, and S_xx
  // is ill-conditioned.
  TwoPosterLinearRig rig;
  rig.noise_m = 20e-6;
  const auto lines = lines_between(0.5, 20.0);
  const auto e = orthogonal_multisines(lines, kTicks, 2, 4, 0.003, 11);
  auto played = played_records(e, 1);
  for (std::size_t i = 0; i < played[1].size(); ++i) played[1][i] = played[0][i] + 0.003 * played[1][i];
  const auto drives = steady_periods(played, e, 1);
  const auto responses = steady_periods(rig.play(played), e, 1);
  const WelchSettings welch{kTicks, kTicks, SpectralWindow::kRectangular, 1.0 / kPeriod};
  const MimoFrf correlated = estimate_mimo_frf(spans(drives), spans(responses), welch, 0.5, 20.0, lines);
  const MimoFrf independent = measure(rig, 4);
  // Judged where the body moves well above the sensor noise: the body modes.
  double partial_correlated = 0.0, partial_independent = 0.0, multiple = 0.0, n = 0.0;
  for (std::size_t k = 0; k < correlated.frequency_hz.size() && correlated.frequency_hz[k] <= 3.0; ++k) {
    partial_correlated += 0.5 * (correlated.partial_coherence[k](0, 0) + correlated.partial_coherence[k](1, 1));
    partial_independent += 0.5 * (independent.partial_coherence[k](0, 0) + independent.partial_coherence[k](1, 1));
    multiple += correlated.multiple_coherence[k].minCoeff();
    n += 1.0;
    EXPECT_GT(correlated.input_condition[k], 100.0);
  }
  EXPECT_GT(partial_independent / n, 0.95);
  EXPECT_LT(partial_correlated / n, 0.5);
  EXPECT_GT(multiple / n, 0.95);
}

TEST(MimoExcitation, RefusesFewerRealisationsThanDrivesAndLinesPastNyquist) {
  EXPECT_THROW(orthogonal_multisines({4, 5}, 100, 2, 1, 1.0, 1), std::invalid_argument);
  EXPECT_THROW(orthogonal_multisines({50}, 100, 2, 2, 1.0, 1), std::invalid_argument);
  const auto e = orthogonal_multisines({4, 5}, 100, 2, 2, 0.5, 1);
  double peak = 0.0;
  for (double v : e.periods[1][1]) peak = std::max(peak, std::abs(v));
  EXPECT_NEAR(peak, 0.5, 1e-12);
}

}  // namespace
}  // namespace rigctl
