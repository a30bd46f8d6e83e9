// What one diagnosis works on (tools/diagnosis/engine.cpp): the rig model,
// the flat parameter layout, the split into an estimation and a held-out
// part, the channel weights and the priors' weight, and the fits and
// scores every round uses. Internal to the diagnosis.
#pragma once

#include <chrono>
#include <ostream>
#include <string>
#include <vector>

#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/parallel.hpp"

namespace rigctl::diag {

struct Scored {
  std::vector<double> theta;
  std::vector<double> sigma;
  std::vector<bool> undetermined;
  std::vector<std::vector<double>> y;
  std::vector<double> fit;  // per output, held-out fit percent
  double est_sse = 0.0;     // weighted data residuals on the estimation part (no prior terms)
  int iterations = 0;       // of the fit that made it (progress and timing)
};

class Workspace {
 public:
  Workspace(const RigModel& model, const DiagnoseOptions& options);

  const RigModel& model;
  const DiagnoseOptions& options;
  const std::vector<EffectSpec> effects;
  std::vector<ParamSpec> specs;      // baseline then every effect, flat
  std::vector<std::size_t> offset;   // of each effect's first parameter
  std::size_t n_base = 0;
  std::size_t n = 0, init = 0, n_est = 0, val_begin = 0;
  std::vector<unsigned char> est_mask;
  std::vector<double> weight;        // per output: 1 / std
  std::vector<double> noise;         // per output: the record's noise floor (evidence.hpp noise_floor)
  std::size_t n_est_values = 0;      // estimation samples x outputs
  double prior_weight = 0.0;         // FitProblem::prior_weight
  mutable ThreadBudget threads;      // options.threads, shared by every parallel loop of the diagnosis

  const std::vector<Output>& outs() const { return model.outputs(); }
  std::vector<double> theta_null() const;  // baseline nominal, every effect at its null
  Scored score(const std::vector<double>& theta) const;
  Scored fit(const std::vector<double>& start, const std::vector<bool>& free, int iterations, bool covariance) const;
  std::vector<bool> free_for(const std::vector<std::size_t>& active) const;  // baseline + these effects
  std::size_t parameter_count(const std::vector<std::size_t>& active) const;
  std::vector<double> residual(const Scored& s, std::size_t output) const;
  double held_out_rms(const Scored& s, std::size_t output) const;  // of the residual
  // Effective sample count of a model's estimation residual (docs/diagnosis.md 5).
  double n_eff(const Scored& s) const;
  // The same on some outputs only (empty: all): their weighted estimation
  // SSE, value count and N_eff (the colour of the first of them).
  struct OnOutputs {
    double sse = 0.0, n_eff = 0.0;
    std::size_t values = 0;
  };
  OnOutputs on_outputs(const Scored& s, const std::vector<std::size_t>& outputs) const;
  // Residual variance per effective sample: the priors' weight.
  double residual_variance(const Scored& s) const;
  void say(const std::string& message) const;

 private:
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace rigctl::diag
