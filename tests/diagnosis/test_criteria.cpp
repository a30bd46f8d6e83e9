// The acceptance criteria of the diagnosis as arithmetic on given series
// (tools/diagnosis/criteria.hpp): the stratified block bootstrap of a
// localised effect, and the lower gain floor of a candidate that takes a
// misfit beyond the noise down to the noise.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tools/diagnosis/criteria.hpp"

namespace rigctl::diag {
namespace {

constexpr std::size_t kN = 2000;

// A held-out record of white noise around zero with a burst (an event, a
// lift-off say) in [b, e); `current` misses the burst, `candidate` has it.
struct Burst {
  std::vector<double> measured, current, candidate;
};

Burst burst_record(std::size_t b, std::size_t e, unsigned seed) {
  Burst r{std::vector<double>(kN), std::vector<double>(kN, 0.0), std::vector<double>(kN, 0.0)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (std::size_t i = 0; i < kN; ++i) {
    const double truth = std::sin(0.01 * static_cast<double>(i)) + (i >= b && i < e ? 0.5 : 0.0);
    r.measured[i] = truth + noise(rng);
    r.current[i] = std::sin(0.01 * static_cast<double>(i));
    r.candidate[i] = truth;
  }
  return r;
}

TEST(DiagnosisCriteria, ActivityStrataMarkTheSubBlocksWhereTheCandidateChangesThePrediction) {
  const auto r = burst_record(400, 700, 1);  // sub-blocks of 200 samples: 2 and 3 hold the burst
  const auto s = activity_strata(r.current, r.candidate, 0, kN, 10);
  ASSERT_EQ(s.size(), 10u);
  for (std::size_t k = 0; k < 10; ++k) EXPECT_EQ(s[k], k == 2 || k == 3 ? 1 : 0) << "sub-block " << k;
}

TEST(DiagnosisCriteria, AGlobalChangeOrASingleActiveSubBlockIsNotStratified) {
  std::vector<double> a(kN, 0.0), b(kN, 0.0);
  for (std::size_t i = 0; i < kN; ++i) b[i] = 0.01 * std::sin(0.05 * static_cast<double>(i));
  EXPECT_TRUE(activity_strata(a, b, 0, kN, 10).empty()) << "a change everywhere: the plain bootstrap";
  const auto one = burst_record(400, 500, 2);
  EXPECT_TRUE(activity_strata(one.current, one.candidate, 0, kN, 10).empty())
      << "one active sub-block has nothing to be resampled among";
  EXPECT_TRUE(activity_strata(a, a, 0, kN, 10).empty()) << "no change at all";
}

TEST(DiagnosisCriteria, StratifiedBootstrapKeepsALocalisedGainInEveryResample) {
  const auto r = burst_record(400, 700, 3);
  const std::vector<const std::vector<double>*> sims{&r.current, &r.candidate};
  const auto plain = bootstrap_fits(r.measured, sims, 0, kN, 400, 7, 10);
  const auto strata = activity_strata(r.current, r.candidate, 0, kN, 10);
  const auto stratified = bootstrap_fits(r.measured, sims, 0, kN, 400, 7, 10, strata);
  const double se_plain = gain_standard_error(plain, 1, 0), se_strat = gain_standard_error(stratified, 1, 0);
  // The plain bootstrap loses both burst blocks in (8/10)^10 = 11 % of its
  // resamples and doubles them in others: most of its spread is the count
  // of events, which the record does not leave to chance.
  EXPECT_LT(se_strat, 0.5 * se_plain) << "plain " << se_plain << " pp, stratified " << se_strat << " pp";
  double worst = 1e9;
  for (const auto& row : stratified) worst = std::min(worst, row[1] - row[0]);
  EXPECT_GT(worst, 0.0) << "every stratified resample keeps the burst the candidate explains";
}

CandidateEvidence evidence(double gain, double excess_before, double excess_after, double fit_before = 99.0) {
  CandidateEvidence c;
  c.gain = gain;
  c.se = 0.1;
  c.significant = true;
  c.bic_new = -1.0;
  c.bic_current = 0.0;
  c.excess_before = excess_before;
  c.excess_after = excess_after;
  c.fit_before = fit_before;
  return c;
}

TEST(DiagnosisCriteria, ASmallGainThatTakesAMisfitDownToTheNoisePasses) {
  const DiagnoseOptions o;
  EXPECT_TRUE(rejection(evidence(0.7, 10.0, 1.1), o).empty()) << rejection(evidence(0.7, 10.0, 1.1), o);
  EXPECT_TRUE(explains_misfit(evidence(0.7, 10.0, 1.1)));
}

TEST(DiagnosisCriteria, ASmallGainWithoutAMisfitToExplainNeedsTheFullFloor) {
  const DiagnoseOptions o;
  // The current model is within the noise: nothing beyond it to explain.
  EXPECT_NE(rejection(evidence(0.7, 3.0, 1.0), o), "");
  // A channel measured far more finely than it moves (fit 99.8 %).
  EXPECT_NE(rejection(evidence(0.7, 10.0, 1.0, 99.8), o), "");
  // It takes away only half of the excess variance: 10 -> 7.1 x the noise.
  EXPECT_FALSE(explains_misfit(evidence(0.7, 10.0, 7.1)));
  EXPECT_NE(rejection(evidence(0.7, 10.0, 7.1), o), "");
  // Below even the lower floor.
  EXPECT_NE(rejection(evidence(0.2, 10.0, 1.0), o), "");
}

TEST(DiagnosisCriteria, TheUnexplainedTestIsTheOneTheGateUses) {
  EXPECT_TRUE(misfits_beyond_noise(kUnexplainedExcess, kUnexplainedFit - 0.1));
  EXPECT_FALSE(misfits_beyond_noise(kUnexplainedExcess - 0.1, 90.0));
  EXPECT_FALSE(misfits_beyond_noise(10.0, kUnexplainedFit));
  // The lower floor opens exactly where a `none` would be `unexplained`: a
  // candidate that takes the residual to the noise from just below the
  // threshold gets the full floor, from the threshold the lower one.
  EXPECT_FALSE(explains_misfit(evidence(0.7, kUnexplainedExcess - 0.01, 1.0)));
  EXPECT_TRUE(explains_misfit(evidence(0.7, kUnexplainedExcess, 1.0)));
  EXPECT_FALSE(explains_misfit(evidence(0.7, 10.0, 1.0, kUnexplainedFit)));
}

}  // namespace
}  // namespace rigctl::diag
