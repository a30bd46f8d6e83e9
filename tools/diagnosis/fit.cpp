// The only translation unit that includes Ceres (slow to compile).
#include "tools/diagnosis/fit.hpp"

#include <ceres/ceres.h>
#include <Eigen/Dense>
#include <glog/logging.h>
#include <memory>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "tools/diagnosis/parallel.hpp"

namespace rigctl::diag {

namespace {

// One past the last sample a fit scores: its replays need go no further.
std::size_t mask_horizon(const std::vector<unsigned char>& mask) {
  std::size_t h = mask.size();
  while (h > 0 && !mask[h - 1]) --h;
  return h;
}

// Fit tolerances: Ceres stops when a step changes the cost or the scaled
// parameters by less than this relative amount. The scores compared
// afterwards are fit percents to 0.01 pp, far coarser.
constexpr double kFitTolerance = 1e-8;
// The Jacobian's finite-difference step, relative to a scaled parameter's
// magnitude (at least kStepFloor of its scale): large enough for a replay
// with switching friction, small against any step the optimiser takes.
constexpr double kRelativeStep = 1e-4;
constexpr double kStepFloor = 0.05;
// A weighted residual is clipped to this (a diverging replay must not
// overflow the cost); a non-finite one counts as it.
constexpr double kResidualClip = 1e6;
// Directions of J^T J with eigenvalues below this share of the largest are
// not identifiable (their parameters get an infinite sigma), and a parameter
// whose share of such a direction's eigenvector exceeds kFlatLoading lies in it.
constexpr double kFlatEigenvalue = 1e-10;
constexpr double kFlatLoading = 0.1;
// With a prior, a parameter is undetermined when its posterior is not
// narrower than this share of the prior (docs/diagnosis.md 4).
constexpr double kDeterminedShare = 0.7;

// The output-error residuals at scaled parameters z: the weighted data
// residuals on the mask, then one residual per free parameter with a prior.
struct Residuals {
  const FitProblem* p = nullptr;
  std::vector<int> free_index;
  std::vector<int> prior_index;  // free parameters with a prior (one residual each, after the data)
  std::size_t count = 0;
  std::size_t horizon = 0;  // replays stop after the last masked sample (RigModel::simulate_prefix)

  void theta_from(const double* z, std::vector<double>& theta) const {
    theta = p->theta0;
    for (std::size_t j = 0; j < free_index.size(); ++j) {
      const auto i = static_cast<std::size_t>(free_index[j]);
      theta[i] = z[j] * p->specs[i].scale;
    }
  }

  void eval(const double* z, double* r) const {
    std::vector<double> theta;
    theta_from(z, theta);
    std::vector<std::vector<double>> y;
    p->model->simulate_prefix(theta, y, horizon);
    const auto& outs = p->model->outputs();
    std::size_t k = 0;
    for (std::size_t o = 0; o < outs.size(); ++o) {
      const auto& m = outs[o].measured;
      for (std::size_t i = 0; i < m.size(); ++i) {
        if (!p->mask[i]) continue;
        const double e = (y[o][i] - m[i]) * p->weight[o];
        r[k++] = std::isfinite(e) ? std::clamp(e, -kResidualClip, kResidualClip) : kResidualClip;
      }
    }
    const double w = std::sqrt(std::max(0.0, p->prior_weight));
    for (int i : prior_index) {
      const auto& sp = p->specs[static_cast<std::size_t>(i)];
      r[k++] = w * (theta[static_cast<std::size_t>(i)] - sp.init) / (sp.prior * std::abs(sp.init));
    }
  }
};

// Finite differences with an explicit step per parameter (the simulation has
// switching friction, so steps are not tiny), clipped to the bounds. While
// the optimiser iterates they are forward differences: one replay per free
// parameter instead of two, and Levenberg-Marquardt only needs a descent
// direction (the O(h) error at h = 1e-4 of the parameter's scale is far
// below the step it takes). The Jacobian of the covariance is central
// (set_central before it), as before: the standard deviations feed the
// strength test.
class SimCost : public ceres::CostFunction {
 public:
  SimCost(const Residuals* r, std::vector<double> lo, std::vector<double> hi, ThreadBudget* threads)
      : r_(r), lo_(std::move(lo)), hi_(std::move(hi)), threads_(threads) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(r->free_index.size()));
    set_num_residuals(static_cast<int>(r->count));
  }
  void set_central(bool central) { central_ = central; }
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const std::size_t nf = r_->free_index.size();
    for (std::size_t j = 0; j < nf; ++j)
      if (!std::isfinite(params[0][j])) return false;
    r_->eval(params[0], residuals);
    if (jacobians == nullptr || jacobians[0] == nullptr) return true;
    // The columns' simulations are independent: they run on the budget's
    // spare threads (the simulations are const and share nothing), each
    // worker with its own buffers.
    const std::size_t workers = threads_ ? threads_->threads() : 1;
    std::vector<std::vector<double>> rp(workers), rm(workers);
    auto column = [&](std::size_t j, std::size_t worker) {
      rp[worker].resize(r_->count);
      rm[worker].resize(r_->count);
      this->column(params[0], residuals, j, rp[worker], rm[worker], jacobians[0]);
    };
    if (threads_) {
      parallel_for(*threads_, nf, column);
    } else {
      for (std::size_t j = 0; j < nf; ++j) column(j, 0);
    }
    return true;
  }

 private:
  // Column j of the Jacobian (row-major, nf columns) at z, whose residuals are f0.
  void column(const double* z0, const double* f0, std::size_t j, std::vector<double>& rp, std::vector<double>& rm,
              double* jac) const {
    const std::size_t nf = r_->free_index.size();
    std::vector<double> z(z0, z0 + nf);
    const double h = kRelativeStep * std::max(std::abs(z[j]), kStepFloor);
    double a = std::min(z[j] + h, hi_[j]), b = z[j];
    if (central_) {
      b = std::max(z[j] - h, lo_[j]);
    } else if (a <= z[j]) {  // at the upper bound: a backward difference
      a = z[j];
      b = std::max(z[j] - h, lo_[j]);
    }
    const double* fa = f0;
    const double* fb = f0;
    if (a != z0[j]) {
      z[j] = a;
      r_->eval(z.data(), rp.data());
      fa = rp.data();
    }
    if (b != z0[j]) {
      z[j] = b;
      r_->eval(z.data(), rm.data());
      fb = rm.data();
    }
    const double d = a - b;
    for (std::size_t i = 0; i < r_->count; ++i) jac[i * nf + j] = d > 0 ? (fa[i] - fb[i]) / d : 0.0;
  }

  const Residuals* r_;
  std::vector<double> lo_, hi_;
  ThreadBudget* threads_;
  bool central_ = false;
};

// One output-error fit in its three parts: the problem's set-up (which
// parameters are free, their scaled start and bounds, the residuals), the
// solve, and the covariance at the optimum. The object owns everything Ceres
// is handed (the problem does not take ownership), so it is neither copied
// nor moved.
class OutputErrorFit {
 public:
  explicit OutputErrorFit(const FitProblem& p);
  OutputErrorFit(const OutputErrorFit&) = delete;
  OutputErrorFit& operator=(const OutputErrorFit&) = delete;

  std::size_t free_count() const { return res_.free_index.size(); }
  // Levenberg-Marquardt from the start; theta, cost and iterations of `out`.
  void solve(FitResult& out);
  // sigma and the undetermined flags of `out`, at out.theta.
  void covariance(FitResult& out);

 private:
  double residual_scale(const FitResult& out) const;

  const FitProblem& p_;
  Residuals res_;
  std::vector<double> z_, zlo_, zhi_;  // scaled parameters and bounds (1e30: none)
  std::unique_ptr<SimCost> cost_;
  std::unique_ptr<ceres::Problem> problem_;
};

OutputErrorFit::OutputErrorFit(const FitProblem& p) : p_(p) {
  res_.p = &p;
  for (std::size_t i = 0; i < p.specs.size(); ++i)
    if (p.free[i]) {
      res_.free_index.push_back(static_cast<int>(i));
      if (p.specs[i].prior > 0.0 && p.specs[i].init != 0.0 && p.prior_weight > 0.0)
        res_.prior_index.push_back(static_cast<int>(i));
    }
  const std::size_t masked = static_cast<std::size_t>(std::count_if(p.mask.begin(), p.mask.end(), [](auto m) { return m != 0; }));
  res_.count = masked * p.model->outputs().size() + res_.prior_index.size();
  res_.horizon = mask_horizon(p.mask);
  const std::size_t nf = free_count();
  if (nf == 0) return;
  z_.resize(nf);
  zlo_.resize(nf);
  zhi_.resize(nf);
  for (std::size_t j = 0; j < nf; ++j) {
    const auto& sp = p.specs[static_cast<std::size_t>(res_.free_index[j])];
    z_[j] = p.theta0[static_cast<std::size_t>(res_.free_index[j])] / sp.scale;
    zlo_[j] = sp.lo > -1e29 ? sp.lo / sp.scale : -1e30;
    zhi_[j] = sp.hi < 1e29 ? sp.hi / sp.scale : 1e30;
  }
  cost_ = std::make_unique<SimCost>(&res_, zlo_, zhi_, p.threads);
  ceres::Problem::Options popt;
  popt.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_ = std::make_unique<ceres::Problem>(popt);
  problem_->AddResidualBlock(cost_.get(), nullptr, z_.data());
  for (std::size_t j = 0; j < nf; ++j) {
    if (zlo_[j] > -1e29) problem_->SetParameterLowerBound(z_.data(), static_cast<int>(j), zlo_[j]);
    if (zhi_[j] < 1e29) problem_->SetParameterUpperBound(z_.data(), static_cast<int>(j), zhi_[j]);
  }
}

void OutputErrorFit::solve(FitResult& out) {
  // Ceres logs through glog: keep the terminal for our progress (once: fits
  // run on several threads).
  static std::once_flag quiet;
  std::call_once(quiet, [] { FLAGS_minloglevel = 3; });
  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::DENSE_QR;
  opt.max_num_iterations = p_.max_iterations;
  opt.function_tolerance = kFitTolerance;
  opt.parameter_tolerance = kFitTolerance;
  opt.num_threads = 1;  // the Jacobian's columns are parallel in SimCost, from the diagnosis's budget
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(opt, problem_.get(), &summary);
  out.cost = summary.final_cost;
  out.iterations = static_cast<int>(summary.iterations.size());
  for (std::size_t j = 0; j < free_count(); ++j) {
    const auto i = static_cast<std::size_t>(res_.free_index[j]);
    out.theta[i] = z_[j] * p_.specs[i].scale;
  }
}

// The residual variance per degree of freedom at the optimum, inflated for
// the colour of the first output's residual (N / N_eff): the covariance's scale.
double OutputErrorFit::residual_scale(const FitResult& out) const {
  std::vector<std::vector<double>> y;
  p_.model->simulate_prefix(out.theta, y, res_.horizon);
  const auto& outs = p_.model->outputs();
  std::vector<double> first;
  double data_sse = 0.0;
  for (std::size_t o = 0; o < outs.size(); ++o)
    for (std::size_t i = 0; i < outs[o].measured.size(); ++i)
      if (p_.mask[i]) {
        const double e = (y[o][i] - outs[o].measured[i]) * p_.weight[o];
        if (o == 0) first.push_back(e);
        if (std::isfinite(e)) data_sse += e * e;
      }
  const double n_data = static_cast<double>(res_.count - res_.prior_index.size());
  const double dof = std::max(1.0, n_data - static_cast<double>(free_count()));
  return data_sse / dof / effective_fraction(first);
}

// (J^T J)^-1 by eigen-decomposition from the central-difference Jacobian at
// the optimum, scaled by the residual variance; directions with eigenvalues
// below kFlatEigenvalue of the largest are not identifiable.
void OutputErrorFit::covariance(FitResult& out) {
  const std::size_t nf = free_count();
  const double s2 = residual_scale(out);
  double cost_now = 0.0;
  ceres::CRSMatrix J;
  cost_->set_central(true);
  problem_->Evaluate(ceres::Problem::EvaluateOptions(), &cost_now, nullptr, nullptr, &J);
  const auto dim = static_cast<Eigen::Index>(nf);
  Eigen::MatrixXd JtJ = Eigen::MatrixXd::Zero(dim, dim);
  for (int row = 0; row < J.num_rows; ++row)
    for (int a1 = J.rows[row]; a1 < J.rows[row + 1]; ++a1)
      for (int b1 = J.rows[row]; b1 < J.rows[row + 1]; ++b1) JtJ(J.cols[a1], J.cols[b1]) += J.values[a1] * J.values[b1];
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(JtJ);
  const auto& ev = es.eigenvalues();
  const double top = ev.size() ? ev.maxCoeff() : 0.0;
  auto flat = [&](Eigen::Index k) { return !(ev(k) > kFlatEigenvalue * top) || !std::isfinite(ev(k)); };
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(dim, dim);
  for (Eigen::Index k = 0; k < ev.size(); ++k) {
    if (flat(k)) {
      out.rank_deficient = true;
      continue;
    }
    C += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / ev(k);
  }
  for (std::size_t j = 0; j < nf; ++j) {
    const auto i = static_cast<std::size_t>(res_.free_index[j]);
    const auto jj = static_cast<Eigen::Index>(j);
    bool weak = false;
    for (Eigen::Index k = 0; k < ev.size(); ++k)
      if (flat(k) && std::abs(es.eigenvectors()(jj, k)) > kFlatLoading) weak = true;
    out.sigma[i] = weak ? std::numeric_limits<double>::infinity()
                        : std::sqrt(std::max(0.0, C(jj, jj) * s2)) * p_.specs[i].scale;
    // With a prior the posterior is always finite: the run did not determine
    // the parameter when it is hardly narrower than the prior. The prior rows
    // carry prior_weight, not s2, so the prior's own width is rescaled.
    const auto& sp = p_.specs[i];
    const bool has_prior = std::find(res_.prior_index.begin(), res_.prior_index.end(), static_cast<int>(i)) !=
                           res_.prior_index.end();
    if (has_prior) {
      const double prior_sd = sp.prior * std::abs(sp.init) * std::sqrt(s2 / p_.prior_weight);
      out.undetermined[i] = !(out.sigma[i] < kDeterminedShare * prior_sd);
    } else {
      out.undetermined[i] = !std::isfinite(out.sigma[i]);
    }
  }
}

}  // namespace

// Effective sample count of a coloured residual: N / (1 + 2 sum rho_k), the
// sum running until the autocorrelation first drops below 0.05 (docs/diagnosis.md 5).
double effective_fraction(const std::vector<double>& r) {
  const std::size_t n = r.size();
  if (n < 10) return 1.0;
  double mean = 0.0;
  for (double v : r) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0.0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  if (c0 <= 0.0) return 1.0;
  double sum = 0.0;
  const std::size_t max_lag = std::min<std::size_t>(n / 4, 2000);
  for (std::size_t k = 1; k < max_lag; ++k) {
    double c = 0.0;
    for (std::size_t i = k; i < n; ++i) c += (r[i] - mean) * (r[i - k] - mean);
    const double rho = c / c0;
    if (rho < 0.05) break;
    sum += rho;
  }
  return 1.0 / (1.0 + 2.0 * sum);
}

double weighted_sse(const RigModel& model, const std::vector<double>& theta, const std::vector<unsigned char>& mask,
                    const std::vector<double>& weight) {
  std::vector<std::vector<double>> y;
  model.simulate_prefix(theta, y, mask_horizon(mask));
  double s = 0.0;
  const auto& outs = model.outputs();
  for (std::size_t o = 0; o < outs.size(); ++o)
    for (std::size_t i = 0; i < outs[o].measured.size(); ++i)
      if (mask[i]) {
        const double e = (y[o][i] - outs[o].measured[i]) * weight[o];
        s += std::isfinite(e) ? e * e : kResidualClip * kResidualClip;
      }
  return s;
}

FitResult fit_output_error(const FitProblem& p, bool with_covariance) {
  FitResult out;
  out.theta = p.theta0;
  out.sigma.assign(p.specs.size(), 0.0);
  out.undetermined.assign(p.specs.size(), false);
  OutputErrorFit fit(p);
  if (fit.free_count() == 0) {
    out.cost = 0.5 * weighted_sse(*p.model, p.theta0, p.mask, p.weight);
    return out;
  }
  fit.solve(out);
  if (with_covariance) fit.covariance(out);
  return out;
}

}  // namespace rigctl::diag
