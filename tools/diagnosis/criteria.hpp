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
//
// With `strata`, each sub-block is resampled only among the sub-blocks of
// its own stratum (a stratified block bootstrap): a localised effect (a
// lift-off burst in two sub-blocks of ten) keeps its number of events in
// every resample instead of losing them all in one resample of nine.
std::vector<std::vector<double>> bootstrap_fits(const std::vector<double>& measured,
                                                const std::vector<const std::vector<double>*>& sims,
                                                std::size_t begin, std::size_t end, int resamples,
                                                unsigned seed, std::size_t blocks = 10,
                                                const std::vector<int>& strata = {});

// Strata for bootstrap_fits: 1 for the sub-blocks where simulation `b`
// differs from `a` (mean square change at least a tenth of the largest
// sub-block's), 0 elsewhere. The split depends on the models' predictions
// only, not on the measurement. Empty (no stratification) when fewer than
// two sub-blocks are active, or all of them are (a global effect: the
// plain block bootstrap).
std::vector<int> activity_strata(const std::vector<double>& a, const std::vector<double>& b, std::size_t begin,
                                 std::size_t end, std::size_t blocks = 10);

// Standard deviation over the resamples of fit(candidate) - fit(current).
double gain_standard_error(const std::vector<std::vector<double>>& fits, std::size_t candidate, std::size_t current);

// What the gates see of one refitted candidate.
struct CandidateEvidence {
  double gain = 0.0;          // held-out fit gain on its best signal [pp]
  double se = 0.0;            // its bootstrap standard error [pp]
  bool significant = false;   // a strength parameter > 3 sigma from its null
  double bic_new = 0.0, bic_current = 0.0;
  // On that signal: the held-out residual's rms over the record's noise
  // floor, with the current model and with the candidate, and the current
  // model's fit percent.
  double excess_before = 0.0, excess_after = 0.0, fit_before = 100.0;
};

// Whether the current model misfits a signal beyond the noise: rms at least
// kUnexplainedExcess x the noise floor and a fit below kUnexplainedFit (a
// channel measured far more finely than it moves does not count). The same
// test makes a `none` verdict `unexplained`.
constexpr double kUnexplainedExcess = 4.0;
constexpr double kUnexplainedFit = 99.5;
bool misfits_beyond_noise(double excess, double fit_percent);

// Whether a candidate explains such a misfit: it removes at least
// kExplainedShare of the residual variance above the noise.
constexpr double kExplainedShare = 0.75;
bool explains_misfit(const CandidateEvidence& c);

// The held-out gain a candidate must reach: explained_min_gain where it
// explains a misfit beyond the noise, else g_min.
double gain_floor(const CandidateEvidence& c, const DiagnoseOptions& o);

// Empty when the candidate passes, else why not. The held-out gain must
// reach g_min and two standard errors; where the current model misfits
// beyond the noise and the candidate explains that misfit (explains_misfit),
// it need only reach explained_min_gain: a small signal in a clean record
// (a 2 ms delay on a body LVDT: 99.2 % -> 99.9 %) is no weak imitation when
// it takes the residual down to the noise. A large held-out gain on
// the effect's own signal (>= strong_gain and >= strong_se standard errors)
// stands on its own: the significance test, whose sigma a smoothed,
// non-convex effect can inflate, cannot veto the obvious.
std::string rejection(const CandidateEvidence& c, const DiagnoseOptions& o);

// Whether two gains are about equal (docs/diagnosis.md 5: ambiguity).
bool about_equal(double gain_a, double gain_b, const DiagnoseOptions& o);

}  // namespace rigctl::diag
