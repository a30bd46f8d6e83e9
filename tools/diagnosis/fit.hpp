// Output-error fitting for the diagnosis (Ceres Solver; the only file that
// includes Ceres is tools/diagnosis/fit.cpp).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tools/diagnosis/model.hpp"

namespace rigctl::diag {

class ThreadBudget;

struct FitProblem {
  const RigModel* model = nullptr;
  std::vector<ParamSpec> specs;     // all parameters (baseline + effects), flat
  std::vector<bool> free;           // which are fitted
  std::vector<double> theta0;       // start
  std::vector<unsigned char> mask;  // samples whose residuals count (estimation part)
  std::vector<double> weight;       // per output: 1 / scale
  int max_iterations = 50;
  // Weight of the priors (ParamSpec::prior): each free parameter with a
  // prior adds the residual sqrt(prior_weight) (theta - init) / (prior init),
  // in the units of the weighted output residuals. The engine sets it to the
  // residual variance per effective sample, so the fit is a MAP estimate.
  double prior_weight = 0.0;
  // The diagnosis's threads (parallel.hpp): the Jacobian's columns borrow the
  // spare ones. Null: one thread.
  ThreadBudget* threads = nullptr;
};

struct FitResult {
  std::vector<double> theta;
  std::vector<double> sigma;  // standard deviation per parameter (0 for fixed ones; inf if not identifiable)
  // Per parameter: the run did not determine it (a flat direction of the
  // fit, or a posterior no narrower than 0.7 x its prior).
  std::vector<bool> undetermined;
  double cost = 0.0;          // 0.5 * sum of squared weighted residuals on the mask
  int iterations = 0;
  bool rank_deficient = false;
};

// Fits the free parameters by output error (free-run simulation over the whole
// record, residuals on the mask). sigma from the Gauss-Newton covariance scaled
// by the residual variance and inflated for coloured residuals (N / N_eff).
FitResult fit_output_error(const FitProblem& problem, bool with_covariance);

// N_eff / N of a coloured residual series (docs/diagnosis.md 5, "Why N_eff").
double effective_fraction(const std::vector<double>& r);

// Weighted residuals of a simulation on the mask (for costs outside Ceres).
double weighted_sse(const RigModel& model, const std::vector<double>& theta, const std::vector<unsigned char>& mask,
                    const std::vector<double>& weight);

}  // namespace rigctl::diag
