#include "tools/diagnosis/workspace.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <mutex>

#include "tools/diagnosis/criteria.hpp"
#include "tools/diagnosis/evidence.hpp"
#include "tools/diagnosis/fit.hpp"

namespace rigctl::diag {

namespace {

// A parameter that stands for a cause calibrates only within its band on
// the cause's side: a move beyond it is not the rig's spread but the cause,
// which its candidate must earn against this baseline (docs/diagnosis.md 4).
void hold_within_cause_band(ParamSpec& sp) {
  if (sp.stands_for.empty() || sp.prior <= 0.0) return;
  const double edge = sp.init * (1.0 + sp.toward * kCauseBandTolerances * sp.prior);
  if (sp.toward < 0) sp.lo = std::max(sp.lo, edge);
  if (sp.toward > 0) sp.hi = std::min(sp.hi, edge);
}

}  // namespace

Workspace::Workspace(const RigModel& m, const DiagnoseOptions& o)
    : model(m),
      options(o),
      effects(m.effects()),
      threads(static_cast<std::size_t>(std::max(1, o.threads))),
      t0_(std::chrono::steady_clock::now()) {
  specs = model.baseline();
  n_base = specs.size();
  // Trending (calibration only): a parameter that stands for a cause is the
  // trend's quantity itself, so its whole departure is fitted.
  if (!o.calibration_only)
    for (auto& sp : specs) hold_within_cause_band(sp);
  for (const auto& e : effects) {
    offset.push_back(specs.size());
    for (const auto& p : e.params) specs.push_back(p);
  }
  n = model.time().size();
  init = std::min(model.init_window(), n / 10);
  n_est = static_cast<std::size_t>(std::floor(static_cast<double>(n) * (1.0 - o.holdout_fraction)));
  val_begin = std::max(n_est, init);
  est_mask.assign(n, 0);
  for (std::size_t i = init; i < n_est; ++i) est_mask[i] = 1;
  for (const auto& out : outs()) {
    double mean = 0.0, ss = 0.0;
    for (double v : out.measured) mean += v;
    mean /= static_cast<double>(n);
    for (double v : out.measured) ss += (v - mean) * (v - mean);
    const double sd = std::sqrt(ss / static_cast<double>(n));
    weight.push_back(sd > 0.0 ? 1.0 / sd : 1.0);
    noise.push_back(noise_floor(out.measured));
  }
  n_est_values = (n_est > init ? n_est - init : 0) * outs().size();
}

std::vector<double> Workspace::theta_null() const {
  std::vector<double> t(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) t[i] = i < n_base ? specs[i].init : specs[i].null;
  return t;
}

Scored Workspace::score(const std::vector<double>& theta) const {
  Scored s;
  s.theta = theta;
  model.simulate(theta, s.y);
  for (std::size_t o = 0; o < outs().size(); ++o) {
    s.fit.push_back(fit_percent(outs()[o].measured, s.y[o], val_begin, n));
    for (std::size_t i = 0; i < n; ++i)
      if (est_mask[i]) {
        const double e = (s.y[o][i] - outs()[o].measured[i]) * weight[o];
        s.est_sse += std::isfinite(e) ? e * e : 1e12;
      }
  }
  return s;
}

Scored Workspace::fit(const std::vector<double>& start, const std::vector<bool>& free, int iterations,
                      bool covariance) const {
  FitProblem p;
  p.model = &model;
  p.specs = specs;
  p.free = free;
  p.theta0 = start;
  p.mask = est_mask;
  p.weight = weight;
  p.max_iterations = iterations;
  p.prior_weight = prior_weight;
  p.threads = &threads;
  const auto r = fit_output_error(p, covariance);
  Scored s = score(r.theta);
  s.sigma = r.sigma;
  s.undetermined = r.undetermined;
  s.iterations = r.iterations;
  return s;
}

std::vector<bool> Workspace::free_for(const std::vector<std::size_t>& active) const {
  std::vector<bool> f(specs.size(), false);
  for (std::size_t i = 0; i < n_base; ++i) f[i] = true;
  for (auto e : active)
    for (std::size_t j = 0; j < effects[e].params.size(); ++j) f[offset[e] + j] = !effects[e].params[j].form;
  return f;
}

// A form index is chosen, not fitted: it does not count.
std::size_t Workspace::parameter_count(const std::vector<std::size_t>& active) const {
  std::size_t k = n_base;
  for (auto e : active)
    for (const auto& p : effects[e].params) k += p.form ? 0 : 1;
  return k;
}

std::vector<double> Workspace::residual(const Scored& s, std::size_t o) const {
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = outs()[o].measured[i] - s.y[o][i];
  return r;
}

double Workspace::held_out_rms(const Scored& s, std::size_t o) const {
  double ss = 0.0;
  for (std::size_t i = val_begin; i < n; ++i) {
    const double e = outs()[o].measured[i] - s.y[o][i];
    ss += e * e;
  }
  return std::sqrt(ss / static_cast<double>(std::max<std::size_t>(1, n - val_begin)));
}

double Workspace::n_eff(const Scored& s) const {
  std::vector<double> r;
  const auto e = residual(s, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (est_mask[i]) r.push_back(e[i] * weight[0]);
  return std::max(10.0, static_cast<double>(n_est_values) * effective_fraction(r));
}

Workspace::OnOutputs Workspace::on_outputs(const Scored& s, const std::vector<std::size_t>& outputs) const {
  if (outputs.empty()) return {s.est_sse, n_eff(s), n_est_values};
  OnOutputs r;
  std::vector<double> first;
  for (std::size_t o : outputs)
    for (std::size_t i = 0; i < n; ++i)
      if (est_mask[i]) {
        const double e = (s.y[o][i] - outs()[o].measured[i]) * weight[o];
        r.sse += std::isfinite(e) ? e * e : 1e12;
        ++r.values;
        if (o == outputs.front()) first.push_back(e);
      }
  r.n_eff = std::max(10.0, static_cast<double>(r.values) * effective_fraction(first));
  return r;
}

double Workspace::residual_variance(const Scored& s) const {
  return s.est_sse / std::max(1.0, n_eff(s));
}

void Workspace::say(const std::string& m) const {
  if (!options.progress) return;
  static std::mutex one_line_at_a_time;  // candidates are fitted on several threads
  std::lock_guard<std::mutex> lock(one_line_at_a_time);
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  *options.progress << "diagnose [" << std::fixed << std::setprecision(1) << t << std::defaultfloat << " s] " << m
                    << std::endl;
}

}  // namespace rigctl::diag
