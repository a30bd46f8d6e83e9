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

#include "tools/diagnosis/parallel.hpp"

namespace rigctl::diag {

namespace {

struct Residuals {
  const FitProblem* p;
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
        r[k++] = std::isfinite(e) ? std::clamp(e, -1e6, 1e6) : 1e6;
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
  explicit SimCost(const Residuals* r, std::vector<double> lo, std::vector<double> hi)
      : r_(r), lo_(std::move(lo)), hi_(std::move(hi)) {
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
    const std::size_t m = r_->count;
    auto column = [&](std::size_t j, std::vector<double>& rp, std::vector<double>& rm) {
      std::vector<double> z(params[0], params[0] + nf);
      const double h = 1e-4 * std::max(std::abs(z[j]), 0.05);
      double a = std::min(z[j] + h, hi_[j]), b = z[j];
      if (central_) {
        b = std::max(z[j] - h, lo_[j]);
      } else if (a <= z[j]) {  // at the upper bound: a backward difference
        a = z[j];
        b = std::max(z[j] - h, lo_[j]);
      }
      const double* fa = residuals;
      const double* fb = residuals;
      if (a != z[j]) {
        z[j] = a;
        r_->eval(z.data(), rp.data());
        fa = rp.data();
      }
      if (b != params[0][j]) {
        z[j] = b;
        r_->eval(z.data(), rm.data());
        fb = rm.data();
      }
      const double d = a - b;
      for (std::size_t i = 0; i < m; ++i) jacobians[0][i * nf + j] = d > 0 ? (fa[i] - fb[i]) / d : 0.0;
    };
    // The columns' simulations are independent: they run on the workers
    // (the simulations are const and share nothing), each with its own
    // buffers.
    std::vector<std::vector<double>> rp(kDiagnosisWorkers, std::vector<double>(m)), rm = rp;
    parallel_for(nf, [&](std::size_t j, std::size_t worker) { column(j, rp[worker], rm[worker]); });
    return true;
  }

 private:
  const Residuals* r_;
  std::vector<double> lo_, hi_;
  bool central_ = false;
};

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

// One past the last sample a fit scores: its replays need go no further.
std::size_t mask_horizon(const std::vector<unsigned char>& mask) {
  std::size_t h = mask.size();
  while (h > 0 && !mask[h - 1]) --h;
  return h;
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
        s += std::isfinite(e) ? e * e : 1e12;
      }
  return s;
}

FitResult fit_output_error(const FitProblem& p, bool with_covariance) {
  auto* res = new Residuals;
  res->p = &p;
  for (std::size_t i = 0; i < p.specs.size(); ++i)
    if (p.free[i]) {
      res->free_index.push_back(static_cast<int>(i));
      if (p.specs[i].prior > 0.0 && p.specs[i].init != 0.0 && p.prior_weight > 0.0)
        res->prior_index.push_back(static_cast<int>(i));
    }
  std::size_t masked = 0;
  for (auto m : p.mask) masked += m ? 1 : 0;
  res->count = masked * p.model->outputs().size() + res->prior_index.size();
  res->horizon = mask_horizon(p.mask);

  FitResult out;
  out.theta = p.theta0;
  out.sigma.assign(p.specs.size(), 0.0);
  out.undetermined.assign(p.specs.size(), false);
  const std::size_t nf = res->free_index.size();
  std::unique_ptr<Residuals> owner(res);
  if (nf == 0) {
    out.cost = 0.5 * weighted_sse(*p.model, p.theta0, p.mask, p.weight);
    return out;
  }
  std::vector<double> z(nf);
  for (std::size_t j = 0; j < nf; ++j) {
    const auto i = static_cast<std::size_t>(res->free_index[j]);
    z[j] = p.theta0[i] / p.specs[i].scale;
  }
  const std::vector<int> free_index = res->free_index;
  const std::size_t count = res->count;

  std::vector<double> zlo(nf), zhi(nf);
  for (std::size_t j = 0; j < nf; ++j) {
    const auto& sp = p.specs[static_cast<std::size_t>(free_index[j])];
    zlo[j] = sp.lo > -1e29 ? sp.lo / sp.scale : -1e30;
    zhi[j] = sp.hi < 1e29 ? sp.hi / sp.scale : 1e30;
  }
  auto* cost = new SimCost(res, zlo, zhi);
  // Ceres logs through glog: keep the terminal for our progress (once: fits
  // run on several threads).
  static std::once_flag quiet;
  std::call_once(quiet, [] { FLAGS_minloglevel = 3; });
  ceres::Problem::Options popt;
  popt.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popt);
  std::unique_ptr<SimCost> cost_owner(cost);
  problem.AddResidualBlock(cost, nullptr, z.data());
  for (std::size_t j = 0; j < nf; ++j) {
    const auto& s = p.specs[static_cast<std::size_t>(free_index[j])];
    if (s.lo > -1e29) problem.SetParameterLowerBound(z.data(), static_cast<int>(j), s.lo / s.scale);
    if (s.hi < 1e29) problem.SetParameterUpperBound(z.data(), static_cast<int>(j), s.hi / s.scale);
  }
  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::DENSE_QR;
  opt.max_num_iterations = p.max_iterations;
  opt.function_tolerance = 1e-8;
  opt.parameter_tolerance = 1e-8;
  opt.num_threads = 1;
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(opt, &problem, &summary);
  out.cost = summary.final_cost;
  out.iterations = static_cast<int>(summary.iterations.size());
  for (std::size_t j = 0; j < nf; ++j) {
    const auto i = static_cast<std::size_t>(free_index[j]);
    out.theta[i] = z[j] * p.specs[i].scale;
  }
  if (!with_covariance) return out;

  // Residual variance and colour for the covariance scaling.
  std::vector<std::vector<double>> y;
  p.model->simulate_prefix(out.theta, y, res->horizon);
  std::vector<double> r;
  const auto& m0 = p.model->outputs()[0].measured;
  for (std::size_t i = 0; i < m0.size(); ++i)
    if (p.mask[i]) r.push_back((y[0][i] - m0[i]) * p.weight[0]);
  double data_sse = 0.0;
  for (std::size_t o = 0; o < p.model->outputs().size(); ++o)
    for (std::size_t i = 0; i < m0.size(); ++i)
      if (p.mask[i]) {
        const double e = (y[o][i] - p.model->outputs()[o].measured[i]) * p.weight[o];
        if (std::isfinite(e)) data_sse += e * e;
      }
  const double n_data = static_cast<double>(count - res->prior_index.size());
  const double dof = std::max(1.0, n_data - static_cast<double>(nf));
  const double s2 = data_sse / dof / effective_fraction(r);

  // Covariance from the Jacobian at the optimum: (J^T J)^-1 by eigen-decomposition;
  // directions with eigenvalues below 1e-10 of the largest are not identifiable.
  double cost_now = 0.0;
  ceres::CRSMatrix J;
  cost->set_central(true);
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost_now, nullptr, nullptr, &J);
  Eigen::MatrixXd JtJ = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(nf), static_cast<Eigen::Index>(nf));
  for (int row = 0; row < J.num_rows; ++row)
    for (int a1 = J.rows[row]; a1 < J.rows[row + 1]; ++a1)
      for (int b1 = J.rows[row]; b1 < J.rows[row + 1]; ++b1) JtJ(J.cols[a1], J.cols[b1]) += J.values[a1] * J.values[b1];
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(JtJ);
  const auto& ev = es.eigenvalues();
  const double top = ev.size() ? ev.maxCoeff() : 0.0;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(JtJ.rows(), JtJ.cols());
  for (Eigen::Index k = 0; k < ev.size(); ++k) {
    if (!(ev(k) > 1e-10 * top) || !std::isfinite(ev(k))) {
      out.rank_deficient = true;
      continue;
    }
    C += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / ev(k);
  }
  for (std::size_t j = 0; j < nf; ++j) {
    const auto i = static_cast<std::size_t>(free_index[j]);
    bool weak = false;
    for (Eigen::Index k = 0; k < ev.size(); ++k)
      if (!(ev(k) > 1e-10 * top) && std::abs(es.eigenvectors()(static_cast<Eigen::Index>(j), k)) > 0.1) weak = true;
    out.sigma[i] = weak ? std::numeric_limits<double>::infinity()
                        : std::sqrt(std::max(0.0, C(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) * s2)) *
                              p.specs[i].scale;
    // With a prior the posterior is always finite: the run did not determine
    // the parameter when it is hardly narrower than the prior. The prior rows
    // carry prior_weight, not s2, so the prior's own width is rescaled.
    const auto& sp = p.specs[i];
    const bool has_prior = std::find(res->prior_index.begin(), res->prior_index.end(), static_cast<int>(i)) !=
                           res->prior_index.end();
    if (has_prior) {
      const double prior_sd = sp.prior * std::abs(sp.init) * std::sqrt(s2 / p.prior_weight);
      out.undetermined[i] = !(out.sigma[i] < 0.7 * prior_sd);
    } else {
      out.undetermined[i] = !std::isfinite(out.sigma[i]);
    }
  }
  return out;
}

}  // namespace rigctl::diag
