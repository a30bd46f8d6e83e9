#include "tools/diagnosis/models/controller_from_record.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace rigctl::diag {

namespace {

struct Regression {
  Eigen::VectorXd coef;
  double rms_config = 0.0, rms_fit = 0.0;
  bool ok = false;
};

// Least squares of u on the columns X over the rows in `use`; rms of the
// residual with the fitted and with the configured coefficients.
Regression regress(const std::vector<std::vector<double>>& X, const std::vector<double>& u,
                   const std::vector<bool>& use, const Eigen::VectorXd& configured) {
  Regression r;
  std::size_t m = 0;
  for (bool b : use) m += b ? 1 : 0;
  const auto k = static_cast<Eigen::Index>(X.size());
  if (m < 50) return r;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(m), k);
  Eigen::VectorXd y(static_cast<Eigen::Index>(m));
  Eigen::Index row = 0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (!use[i]) continue;
    for (Eigen::Index c = 0; c < k; ++c) A(row, c) = X[static_cast<std::size_t>(c)][i];
    y(row++) = u[i];
  }
  r.coef = A.colPivHouseholderQr().solve(y);
  r.rms_fit = std::sqrt((A * r.coef - y).squaredNorm() / static_cast<double>(m));
  r.rms_config = std::sqrt((A * configured - y).squaredNorm() / static_cast<double>(m));
  r.ok = r.coef.allFinite();
  return r;
}

// The record's gains replace the config's when they explain the command at
// least three times better (a retuned loop, not the DAC's rounding).
bool prefer_record(const Regression& r) { return r.ok && r.rms_fit * 3.0 < r.rms_config; }

std::string num(double v) {
  std::ostringstream os;
  os << std::setprecision(4) << v;
  return os.str();
}

}  // namespace

std::string calibrate_pi(PiConfig& pi, const std::vector<double>& x_ref, const std::vector<double>& x_r,
                         const std::vector<double>& u) {
  const std::size_t n = u.size();
  std::vector<std::vector<double>> X(2, std::vector<double>(n));
  std::vector<double> u_feedback(n);  // the command less the config's demand feedforward (not regressed)
  std::vector<bool> use(n, true);
  double sum = 0.0;
  bool saturated = false;
  for (std::size_t i = 0; i < n; ++i) {
    const double e = x_ref[i] - x_r[i];
    sum += e * pi.period_s;
    X[0][i] = e;
    X[1][i] = sum;
    const double demand_rate = i > 0 ? (x_ref[i] - x_ref[i - 1]) / pi.period_s : 0.0;
    u_feedback[i] = u[i] - pi.velocity_feedforward * demand_rate;
    saturated = saturated || std::abs(u[i]) >= 0.999 * pi.output_limit;  // anti-windup changes the sum after it
    use[i] = !saturated;
  }
  Eigen::VectorXd cfg(2);
  cfg << pi.kp, pi.ki;
  const auto r = regress(X, u_feedback, use, cfg);
  if (!prefer_record(r)) return "PI gains of the config (kp " + num(pi.kp) + ", ki " + num(pi.ki) + ")";
  pi.kp = r.coef(0);
  pi.ki = r.coef(1);
  return "PI gains read from the record's command (kp " + num(pi.kp) + ", ki " + num(pi.ki) + "; residual " +
         num(r.rms_fit) + " vs " + num(r.rms_config) + " with the config's)";
}

std::string calibrate_pvp(PvpConfig& pvp, const std::vector<double>& theta_d, const std::vector<double>& theta,
                          const std::vector<double>& dp, const std::vector<double>& u) {
  const std::size_t n = u.size();
  std::vector<std::vector<double>> X(3, std::vector<double>(n));
  std::vector<bool> use(n, false);
  const double alpha = pvp.velocity_filter_tau > 0.0 ? 1.0 - std::exp(-pvp.period_s / pvp.velocity_filter_tau) : 1.0;
  const double hp = pvp.tau_f / (pvp.tau_f + pvp.period_s);
  double omega = 0.0, transient = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double last_a = i ? theta[i - 1] : theta[0], last_p = i ? dp[i - 1] : dp[0];
    omega += alpha * ((theta[i] - last_a) / pvp.period_s - omega);
    transient = hp * (transient + dp[i] - last_p);
    X[0][i] = theta_d[i] - theta[i];
    X[1][i] = -(pvp.transient_pressure ? transient : dp[i]);
    X[2][i] = -omega;
    use[i] = std::abs(u[i]) < 0.999 * pvp.output_limit;
  }
  // Pressure gains are V/Pa (1e-5 for 1 V/bar): scale the column for the solver.
  for (auto& v : X[1]) v *= 1e-5;
  Eigen::VectorXd cfg(3);
  cfg << pvp.ke, pvp.kp * 1e5, pvp.kv;
  const auto r = regress(X, u, use, cfg);
  if (!prefer_record(r))
    return "P+V+dP gains of the config (ke " + num(pvp.ke) + ", kv " + num(pvp.kv) + ", kp " + num(pvp.kp) + ")";
  pvp.ke = r.coef(0);
  pvp.kp = std::max(0.0, r.coef(1) * 1e-5);
  pvp.kv = std::max(0.0, r.coef(2));
  return "P+V+dP gains read from the record's command (ke " + num(pvp.ke) + ", kv " + num(pvp.kv) + ", kp " +
         num(pvp.kp) + " V/Pa; residual " + num(r.rms_fit) + " V vs " + num(r.rms_config) + " V with the config's)";
}

}  // namespace rigctl::diag
