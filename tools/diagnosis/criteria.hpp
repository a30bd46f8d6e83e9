// The acceptance criteria of the diagnosis (docs/diagnosis.md 5), each a
// small function: fit percent, BIC with the effective sample count, one
// block bootstrap of the held-out part (the gain's standard error and the
// confidence both come from it), and the decision on one candidate.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tools/diagnosis/engine.hpp"

namespace rigctl::diag {

// BIC of a model with k parameters whose estimation residual has weighted
// sum of squares sse over n values, judged at n_eff effective samples.
double bic(double sse, std::size_t k, double n_eff, std::size_t n);

// Block bootstrap of the held-out part [begin, end) of `measured`: `blocks`
// contiguous sub-blocks resampled with replacement `resamples` times; for
// each resample, the fit percent of every simulation in `sims` (the
// denominator is the whole held-out variance, so a sub-block with little
// motion does not swing it). result[r][s].
std::vector<std::vector<double>> bootstrap_fits(const std::vector<double>& measured,
                                                const std::vector<const std::vector<double>*>& sims,
                                                std::size_t begin, std::size_t end, int resamples,
                                                unsigned seed, std::size_t blocks = 10);

// Standard deviation over the resamples of fit(candidate) - fit(current).
double gain_standard_error(const std::vector<std::vector<double>>& fits, std::size_t candidate, std::size_t current);

// What the gates see of one refitted candidate.
struct CandidateEvidence {
  double gain = 0.0;          // held-out fit gain on its best signal [pp]
  double se = 0.0;            // its bootstrap standard error [pp]
  bool significant = false;   // a strength parameter > 3 sigma from its null
  double bic_new = 0.0, bic_current = 0.0;
};

// Empty when the candidate passes, else why not. A large held-out gain on
// the effect's own signal (>= strong_gain and >= strong_se standard errors)
// stands on its own: the significance test, whose sigma a smoothed,
// non-convex effect can inflate, cannot veto the obvious.
std::string rejection(const CandidateEvidence& c, const DiagnoseOptions& o);

// Whether two gains are about equal (docs/diagnosis.md 5: ambiguity).
bool about_equal(double gain_a, double gain_b, const DiagnoseOptions& o);

}  // namespace rigctl::diag
