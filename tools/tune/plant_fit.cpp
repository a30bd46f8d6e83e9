#include "tools/tune/plant_fit.hpp"

#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "tools/tune/plant_grid.hpp"

namespace rigctl {

namespace {

constexpr int kIterations = 10;
constexpr std::size_t kMaxOrder = 4;

// 1 + d_1 x + d_2 x^2 + ...
Complex denominator(const std::vector<double>& d, Complex x) {
  Complex v = 1.0, p = 1.0;
  for (double di : d) {
    p *= x;
    v += di * p;
  }
  return v;
}

// n_0 + n_1 x + ...
Complex numerator(const std::vector<double>& n, Complex x) {
  Complex v = 0.0, p = 1.0;
  for (double ni : n) {
    v += ni * p;
    p *= x;
  }
  return v;
}

struct Points {
  std::vector<Complex> x, position, pressure;  // x = j w / w0; delay-corrected FRFs
  std::vector<double> weight;
};

Points coherent_points(const PlantResponse& m, double period_s, double w0) {
  Points p;
  for (std::size_t i = 0; i < m.frequency_hz.size(); ++i) {
    if (m.coherence[i] < kDesignCoherence) continue;
    const double w = 2.0 * std::numbers::pi * m.frequency_hz[i];
    const Complex undelay = std::polar(1.0, 0.5 * w * period_s);  // the zero-order hold's half period
    p.x.emplace_back(0.0, w / w0);
    p.position.push_back(m.position[i] * undelay);
    if (!m.pressure.empty()) p.pressure.push_back(m.pressure[i] * undelay);
    p.weight.push_back(m.coherence[i]);
  }
  return p;
}

// One linearised step: D G_y - N_y = 0, D G_p - N_p = 0, rows scaled by
// 1 / |D_previous G| (Sanathanan-Koerner) so every point counts relatively.
PlantModel levy_step(const Points& p, std::size_t na, bool integrating, const PlantModel& previous) {
  const bool pressure = !p.pressure.empty();
  const std::size_t nb = na;  // numerator terms x^0 .. x^(na-1)
  const std::size_t outputs = pressure ? 2 : 1;
  const auto cols = static_cast<Eigen::Index>(na + nb * outputs);
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(2 * outputs * p.x.size()), cols);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m.rows());
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < p.x.size(); ++k) {
    const Complex x = p.x[k];
    const Complex d_prev = denominator(previous.d, x);
    for (std::size_t o = 0; o < outputs; ++o) {
      const Complex g = o == 0 ? (integrating ? x * p.position[k] : p.position[k]) : p.pressure[k];
      const double w = p.weight[k] / std::max(std::abs(d_prev * g), 1e-300);
      std::vector<Complex> coef(static_cast<std::size_t>(cols), 0.0);
      Complex xp = 1.0;
      for (std::size_t i = 0; i < na; ++i) {
        xp *= x;
        coef[i] = g * xp;
      }
      xp = 1.0;
      for (std::size_t i = 0; i < nb; ++i) {
        coef[na + o * nb + i] = -xp;
        xp *= x;
      }
      for (Eigen::Index c = 0; c < cols; ++c) {
        m(row, c) = w * coef[static_cast<std::size_t>(c)].real();
        m(row + 1, c) = w * coef[static_cast<std::size_t>(c)].imag();
      }
      rhs(row) = -w * g.real();
      rhs(row + 1) = -w * g.imag();
      row += 2;
    }
  }
  const Eigen::VectorXd sol = m.colPivHouseholderQr().solve(rhs);
  PlantModel out;
  out.integrating = integrating;
  out.d.assign(sol.data(), sol.data() + na);
  out.n_position.assign(sol.data() + na, sol.data() + na + nb);
  if (pressure) out.n_pressure.assign(sol.data() + na + nb, sol.data() + na + 2 * nb);
  return out;
}

// Roots of D (in x) in the open left half plane.
bool stable(const std::vector<double>& d) {
  const auto n = static_cast<Eigen::Index>(d.size());
  if (n == 0) return true;
  if (d.back() == 0.0) return false;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) companion(0, i) = -(i + 1 < n ? d[static_cast<std::size_t>(n - 2 - i)] : 1.0) / d.back();
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  // A pole at the origin within fitting noise is the rigs' integrator: allowed.
  return companion.eigenvalues().real().maxCoeff() < 1e-3;
}

double rms_error_db(const PlantModel& m, const Points& p) {
  double sum = 0.0;
  for (std::size_t k = 0; k < p.x.size(); ++k) {
    const Complex model = numerator(m.n_position, p.x[k]) / (denominator(m.d, p.x[k]) * (m.integrating ? p.x[k] : 1.0));
    sum += std::norm(std::log(model / p.position[k])) * std::pow(20.0 / std::log(10.0), 2);
  }
  return std::sqrt(sum / static_cast<double>(p.x.size()));
}

// Controllable canonical form of the common denominator D(x) in scaled
// time, then (below) real time and the zero-order hold over one period.
void discretise(PlantModel& m, double period_s) {
  // The common denominator P(x) = D(x), or x D(x) for an integrating plant
  // (whose pressure numerator then gains a factor x).
  const std::size_t shift = m.integrating ? 1 : 0;
  std::vector<double> den(m.d.size() + 1 + shift, 0.0);  // coefficients of x^0 ..
  den[shift] = 1.0;
  for (std::size_t i = 0; i < m.d.size(); ++i) den[shift + 1 + i] = m.d[i];
  const auto N = static_cast<Eigen::Index>(den.size() - 1);
  const double lead = den.back();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(N, N), b = Eigen::MatrixXd::Zero(N, 1);
  for (Eigen::Index i = 0; i + 1 < N; ++i) a(i, i + 1) = 1.0;
  for (Eigen::Index j = 0; j < N; ++j) a(N - 1, j) = -den[static_cast<std::size_t>(j)] / lead;
  b(N - 1, 0) = 1.0 / lead;
  m.c = Eigen::MatrixXd::Zero(m.has_pressure() ? 2 : 1, N);
  for (std::size_t i = 0; i < m.n_position.size(); ++i) m.c(0, static_cast<Eigen::Index>(i)) = m.n_position[i];
  for (std::size_t i = 0; i < m.n_pressure.size(); ++i) m.c(1, static_cast<Eigen::Index>(i + shift)) = m.n_pressure[i];
  // Time scaled by w0: d/dt = w0 d/dtau.
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(N + 1, N + 1);
  aug.topLeftCorner(N, N) = m.w0 * a * period_s;
  aug.topRightCorner(N, 1) = m.w0 * b * period_s;
  const Eigen::MatrixXd e = aug.exp();
  m.phi = e.topLeftCorner(N, N);
  m.gamma = e.topRightCorner(N, 1);
}

}  // namespace

PlantModel fit_plant(const PlantResponse& measured, double period_s) {
  std::vector<double> coherent;
  for (std::size_t i = 0; i < measured.frequency_hz.size(); ++i) {
    if (measured.coherence[i] >= kDesignCoherence) coherent.push_back(measured.frequency_hz[i]);
  }
  if (coherent.size() < 4) throw std::runtime_error("too few coherent FRF points to fit a model");
  const double w0 = 2.0 * std::numbers::pi * std::sqrt(coherent.front() * coherent.back());
  const Points p = coherent_points(measured, period_s, w0);
  std::optional<PlantModel> best;
  for (const bool integrating : {true, false}) {
    for (std::size_t na = 1; na <= kMaxOrder && na + 1 <= p.x.size(); ++na) {
      PlantModel m;
      for (int it = 0; it < kIterations; ++it) m = levy_step(p, na, integrating, m);
      if (!stable(m.d)) continue;
      m.w0 = w0;
      m.rms_error_db = rms_error_db(m, p);
      // A higher order or the other structure must earn its place.
      if (!best || m.rms_error_db < best->rms_error_db - 0.1) best = m;
      if (best->rms_error_db < 0.5) break;
    }
  }
  if (!best) throw std::runtime_error("no stable model fits the measured plant");
  discretise(*best, period_s);
  return *best;
}

Complex model_position(const PlantModel& m, double f_hz) {
  const Complex x(0.0, 2.0 * std::numbers::pi * f_hz / m.w0);
  return numerator(m.n_position, x) / (denominator(m.d, x) * (m.integrating ? x : 1.0));
}

}  // namespace rigctl
