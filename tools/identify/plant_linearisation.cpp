#include "tools/identify/plant_linearisation.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "plant/quarter_car/quarter_car_plant.hpp"

namespace rigctl {

namespace {

using QC = QuarterCarPlant;
constexpr std::size_t kXs = 0, kP1 = 1, kP2 = 2, kXr = 3, kVr = 4, kXw = 5, kXb = 7;

// Perturbation per state for central differences: about 1e-6 of each
// state's working scale (spool fraction, Pa, m, m/s).
constexpr std::array<double, QC::kN> kScale{1.0, 2e7, 2e7, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1};

QC::Vec derivative(const QC& plant, const QC::Vec& y, BearingMode mode, double u) {
  QC::Vec dy{};
  plant.derivatives(y, mode, u, dy);
  return dy;
}

// The spool, chamber pressures and command at which the rod rests at x_r:
// Newton on (dx_s, dp1, dp2, dv_r) = 0 from the leakage-balanced rest.
std::pair<QC::Vec, double> equilibrium(const QC& plant, double x_r) {
  const QuarterCarState rest = QC::rest_state(plant.params());
  QC::Vec y = QC::to_vec(rest);
  y[kXr] = y[kXw] = y[kXb] = x_r;
  double u = rest.x_s;
  const std::array<std::size_t, 3> unknown{kXs, kP1, kP2};
  const std::array<std::size_t, 4> equation{kXs, kP1, kP2, kVr};
  for (int iteration = 0; iteration < 50; ++iteration) {
    const BearingMode mode = plant.mode_at_rest(y);
    const QC::Vec f = derivative(plant, y, mode, u);
    Eigen::Vector4d g;
    for (int i = 0; i < 4; ++i) g[i] = f[equation[static_cast<std::size_t>(i)]];
    Eigen::Matrix4d j;
    for (int k = 0; k < 4; ++k) {
      QC::Vec yp = y, ym = y;
      double up = u, um = u;
      const double h = 1e-7 * (k < 3 ? kScale[unknown[static_cast<std::size_t>(k)]] : 1.0);
      if (k < 3) {
        yp[unknown[static_cast<std::size_t>(k)]] += h;
        ym[unknown[static_cast<std::size_t>(k)]] -= h;
      } else {
        up += h;
        um -= h;
      }
      const QC::Vec fp = derivative(plant, yp, mode, up), fm = derivative(plant, ym, mode, um);
      for (int i = 0; i < 4; ++i) j(i, k) = (fp[equation[static_cast<std::size_t>(i)]] - fm[equation[static_cast<std::size_t>(i)]]) / (2 * h);
    }
    const Eigen::Vector4d step = j.fullPivLu().solve(-g);
    for (int k = 0; k < 3; ++k) y[unknown[static_cast<std::size_t>(k)]] += step[k];
    u += step[3];
    if (std::abs(step[1]) + std::abs(step[2]) < 1e-3 && std::abs(step[0]) + std::abs(step[3]) < 1e-12) break;
  }
  return {y, u};
}

int output_row(const std::string& name) {
  if (name == "x_r") return static_cast<int>(kXr);
  if (name == "p1") return static_cast<int>(kP1);
  if (name == "p2") return static_cast<int>(kP2);
  if (name == "x_w") return static_cast<int>(kXw);  // the drive iteration's wheel-displacement target
  if (name == "x_b") return static_cast<int>(kXb);
  throw std::invalid_argument("the quarter car's linearisation has no output '" + name + "' (outputs: x_r, x_w, x_b, p1, p2)");
}

}  // namespace

LinearPlant linearise_quarter_car(const QuarterCarParams& params, double x_r, const std::vector<std::string>& outputs) {
  const QC plant(params);
  const auto [y0, u0] = equilibrium(plant, x_r);
  const BearingMode mode = plant.mode_at_rest(y0);
  const auto n = static_cast<Eigen::Index>(QC::kN);
  LinearPlant m;
  m.a = Eigen::MatrixXd::Zero(n, n);
  m.b = Eigen::MatrixXd::Zero(n, 1);
  for (std::size_t k = 0; k < QC::kN; ++k) {
    QC::Vec yp = y0, ym = y0;
    const double h = 1e-6 * kScale[k];
    yp[k] += h;
    ym[k] -= h;
    const QC::Vec fp = derivative(plant, yp, mode, u0), fm = derivative(plant, ym, mode, u0);
    for (std::size_t i = 0; i < QC::kN; ++i) m.a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = (fp[i] - fm[i]) / (2 * h);
  }
  const double hu = 1e-6;
  const QC::Vec fp = derivative(plant, y0, mode, u0 + hu), fm = derivative(plant, y0, mode, u0 - hu);
  for (std::size_t i = 0; i < QC::kN; ++i) m.b(static_cast<Eigen::Index>(i), 0) = (fp[i] - fm[i]) / (2 * hu);
  m.c = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(outputs.size()), n);
  for (std::size_t r = 0; r < outputs.size(); ++r) m.c(static_cast<Eigen::Index>(r), output_row(outputs[r])) = 1.0;
  m.outputs = outputs;
  m.command = u0;
  return m;
}

std::vector<FrfCurve> sampled_frf(const LinearPlant& p, double period_s, const std::vector<double>& frequency_hz) {
  const Eigen::Index n = p.a.rows();
  // States of very different sizes (Pa beside m) make A badly scaled for
  // the exponential: balance it first (x = D x'), the FRF is unchanged.
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  for (int sweep = 0; sweep < 10; ++sweep) {
    for (Eigen::Index i = 0; i < n; ++i) {
      double row = 0.0, col = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        row += std::abs(p.a(i, j) * d(j) / d(i));
        col += std::abs(p.a(j, i) * d(i) / d(j));
      }
      if (row > 0.0 && col > 0.0) d(i) *= std::sqrt(row / col);
    }
  }
  const Eigen::MatrixXd a = d.asDiagonal().inverse() * p.a * d.asDiagonal();
  const Eigen::MatrixXd b = d.asDiagonal().inverse() * p.b;
  const Eigen::MatrixXd c = p.c * d.asDiagonal();
  // Zero-order hold: exp([[A, B], [0, 0]] T) = [[Phi, Gamma], [0, I]].
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
  aug.topLeftCorner(n, n) = a * period_s;
  aug.topRightCorner(n, 1) = b * period_s;
  const Eigen::MatrixXd e = aug.exp();
  const Eigen::MatrixXcd phi = e.topLeftCorner(n, n).cast<std::complex<double>>();
  const Eigen::VectorXcd gamma = e.topRightCorner(n, 1).cast<std::complex<double>>();
  std::vector<FrfCurve> out(p.outputs.size());
  for (std::size_t r = 0; r < out.size(); ++r) out[r].response = p.outputs[r];
  for (double f : frequency_hz) {
    const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f * period_s);
    const Eigen::MatrixXcd m = z * Eigen::MatrixXcd::Identity(n, n) - phi;
    const Eigen::VectorXcd x = m.fullPivLu().solve(gamma);
    const Eigen::VectorXcd y = c.cast<std::complex<double>>() * x;
    for (std::size_t r = 0; r < out.size(); ++r) out[r].value.push_back(y[static_cast<Eigen::Index>(r)]);
  }
  return out;
}

std::vector<FrfCurve> linearised_plant_frf(const RigConfig& config, double operating_point,
                                           const std::vector<std::string>& responses,
                                           const std::vector<double>& frequency_hz) {
  switch (config.rig) {
    case RigKind::kQuarterCar:
      return sampled_frf(linearise_quarter_car(config.quarter_car, operating_point, responses), config.loop.period_s,
                         frequency_hz);
    // The pneumatic servo's bladder hysteresis and brake are stick/slip
    // elements with no derivative at rest, and the half car is not a
    // position loop: no linearisation to compare with.
    case RigKind::kPneumaticRotary:
    case RigKind::kHalfCar:
    case RigKind::kTwoPoster: return {};  // two drives: its linearisation is the MIMO one (tools/identify/mimo_*)
  }
  return {};
}

}  // namespace rigctl
