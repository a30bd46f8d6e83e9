#include "tools/tune/plant_fit.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>

#include "tools/tune/plant_grid.hpp"

namespace rigctl {

namespace {

constexpr std::size_t kNumeratorTerms = 3;  // b_1 .. b_3: the valve lag and the sample delays
constexpr int kIterations = 8;

Complex poly(const std::vector<double>& c, Complex zi, bool leading_one) {
  Complex v = leading_one ? 1.0 : 0.0, p = 1.0;
  for (double x : c) {
    p *= zi;
    v += x * p;
  }
  return v;
}

struct Points {
  std::vector<Complex> zi, position, pressure;
  std::vector<double> weight;
};

Points coherent_points(const PlantResponse& m, double period_s) {
  Points p;
  for (std::size_t i = 0; i < m.frequency_hz.size(); ++i) {
    if (m.coherence[i] < kDesignCoherence) continue;
    p.zi.push_back(std::polar(1.0, -2.0 * std::numbers::pi * m.frequency_hz[i] * period_s));
    p.position.push_back(m.position[i]);
    if (!m.pressure.empty()) p.pressure.push_back(m.pressure[i]);
    p.weight.push_back(m.coherence[i]);
  }
  return p;
}

// One linearised least-squares step: D G - N = 0 at every point, each row
// divided by |D_previous G| so that every point counts in relative terms.
PlantModel levy_step(const Points& p, std::size_t na, const PlantModel& previous) {
  const bool pressure = !p.pressure.empty();
  const std::size_t nb = kNumeratorTerms;
  const auto cols = static_cast<Eigen::Index>(na + nb * (pressure ? 2 : 1));
  const std::size_t outputs = pressure ? 2 : 1;
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(2 * outputs * p.zi.size()), cols);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m.rows());
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < p.zi.size(); ++k) {
    const Complex zi = p.zi[k];
    const Complex a_prev = poly(previous.a, zi, true);
    for (std::size_t o = 0; o < outputs; ++o) {
      // position: (1 - z^-1) A G = B_y; pressure: A G = B_p
      const Complex g = (o == 0 ? (1.0 - zi) * p.position[k] : p.pressure[k]);
      const double w = p.weight[k] / std::max(std::abs(a_prev * g), 1e-300);
      Complex zp = 1.0;
      std::vector<Complex> coef(static_cast<std::size_t>(cols), 0.0);
      for (std::size_t i = 0; i < na; ++i) {
        zp *= zi;
        coef[i] = g * zp;
      }
      zp = 1.0;
      for (std::size_t i = 0; i < nb; ++i) {
        zp *= zi;
        coef[na + o * nb + i] = -zp;
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
  const Eigen::VectorXd x = m.colPivHouseholderQr().solve(rhs);
  PlantModel out;
  out.a.assign(x.data(), x.data() + na);
  out.b_position.assign(x.data() + na, x.data() + na + nb);
  if (pressure) out.b_pressure.assign(x.data() + na + nb, x.data() + na + 2 * nb);
  return out;
}

bool stable(const std::vector<double>& a) {
  if (a.empty()) return true;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(a.size()), static_cast<Eigen::Index>(a.size()));
  for (std::size_t i = 0; i < a.size(); ++i) companion(0, static_cast<Eigen::Index>(i)) = -a[i];
  for (std::size_t i = 1; i < a.size(); ++i) companion(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i - 1)) = 1.0;
  return companion.eigenvalues().cwiseAbs().maxCoeff() < 1.0;
}

double rms_error_db(const PlantModel& m, const Points& p) {
  double sum = 0.0;
  for (std::size_t k = 0; k < p.zi.size(); ++k) {
    const Complex model = poly(m.b_position, p.zi[k], false) / ((1.0 - p.zi[k]) * poly(m.a, p.zi[k], true));
    sum += std::norm(std::log(model / p.position[k])) * std::pow(20.0 / std::log(10.0), 2);
  }
  return std::sqrt(sum / static_cast<double>(p.zi.size()));
}

}  // namespace

PlantModel fit_plant(const PlantResponse& measured, double period_s) {
  const Points p = coherent_points(measured, period_s);
  if (p.zi.size() < 2 * kNumeratorTerms + 4) throw std::runtime_error("too few coherent FRF points to fit a model");
  std::optional<PlantModel> best;
  for (std::size_t na = 1; na <= 4; ++na) {
    PlantModel m;
    for (int it = 0; it < kIterations; ++it) m = levy_step(p, na, m);
    if (!stable(m.a)) continue;
    m.rms_error_db = rms_error_db(m, p);
    if (!best || m.rms_error_db < best->rms_error_db - 0.05) best = m;
    if (best->rms_error_db < 1.0) break;
  }
  if (!best) throw std::runtime_error("no stable model fits the measured plant");
  return *best;
}

Complex model_position(const PlantModel& m, double f_hz, double period_s) {
  const Complex zi = std::polar(1.0, -2.0 * std::numbers::pi * f_hz * period_s);
  return poly(m.b_position, zi, false) / ((1.0 - zi) * poly(m.a, zi, true));
}

}  // namespace rigctl
