#include "plant/half_car/half_car_model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace rigctl {

namespace {

Eigen::Vector4d corner_vector(double lever, int wheel) {
  Eigen::Vector4d g(1.0, lever, 0.0, 0.0);
  g(2 + wheel) = -1.0;
  return g;
}

}  // namespace

HalfCarModel HalfCarModel::build(const HalfCarParams& p) {
  validate(p);
  HalfCarModel m;
  m.lever_arm[0] = half_car_lever_arm(p, 0);
  m.lever_arm[1] = half_car_lever_arm(p, 1);
  const double k[2] = {p.spring_1, p.spring_2};
  const double c[2] = {p.damper_1, p.damper_2};
  const double kt[2] = {p.tyre_stiffness_1, p.tyre_stiffness_2};
  const double ct[2] = {p.tyre_damping_1, p.tyre_damping_2};

  m.M = Mat4::Zero();
  m.M.diagonal() << p.mass_body, p.inertia_body, p.mass_unsprung_1, p.mass_unsprung_2;
  m.K = Mat4::Zero();
  m.C = Mat4::Zero();
  Eigen::Matrix<double, 4, 2> kr = Eigen::Matrix<double, 4, 2>::Zero();
  Eigen::Matrix<double, 4, 2> cr = Eigen::Matrix<double, 4, 2>::Zero();
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector4d g = corner_vector(m.lever_arm[i], i);
    m.K += k[i] * g * g.transpose();
    m.C += c[i] * g * g.transpose();
    m.K(2 + i, 2 + i) += kt[i];
    m.C(2 + i, 2 + i) += ct[i];
    m.G.col(i) = g;
    kr(2 + i, i) = kt[i];
    cr(2 + i, i) = ct[i];
  }
  const Mat4 m_inv = m.M.inverse();  // diagonal
  m.A = Mat8::Zero();
  m.A.topRightCorner<4, 4>() = Mat4::Identity();
  m.A.bottomLeftCorner<4, 4>() = -m_inv * m.K;
  m.A.bottomRightCorner<4, 4>() = -m_inv * m.C;
  m.B = Mat82::Zero();
  m.B.bottomRows<4>() = m_inv * m.G;
  m.E = Mat82::Zero();
  m.E.bottomRows<4>() = m_inv * kr;
  m.E_rate = Mat82::Zero();
  m.E_rate.bottomRows<4>() = m_inv * cr;
  m.e_roll = Eigen::Matrix<double, 8, 1>::Zero();
  m.e_roll(half_car_state::kOmega) = 1.0 / p.inertia_body;
  return m;
}

Eigen::Matrix<double, 1, 8> HalfCarModel::suspension_travel_row(int wheel) const {
  Eigen::Matrix<double, 1, 8> r = Eigen::Matrix<double, 1, 8>::Zero();
  r.head<4>() = corner_vector(lever_arm[wheel], wheel).transpose();
  return r;
}

std::vector<HalfCarMode> HalfCarModel::modes() const {
  Eigen::EigenSolver<Mat8> solver(A);
  std::vector<HalfCarMode> out;
  for (int j = 0; j < 8; ++j) {
    const std::complex<double> lambda = solver.eigenvalues()(j);
    if (lambda.imag() <= 0.0) continue;
    HalfCarMode mode;
    const double wn = std::abs(lambda);
    mode.natural_hz = wn / (2.0 * std::numbers::pi);
    mode.damped_hz = lambda.imag() / (2.0 * std::numbers::pi);
    mode.damping_ratio = -lambda.real() / wn;
    const auto v = solver.eigenvectors().col(j);
    double best = -1.0;
    for (int d = 0; d < 4; ++d) {
      const double energy = std::norm(v(d)) * M(d, d);
      if (energy > best) {
        best = energy;
        mode.dominant = static_cast<HalfCarDof>(d);
      }
    }
    out.push_back(mode);
  }
  std::sort(out.begin(), out.end(), [](const HalfCarMode& a, const HalfCarMode& b) { return a.natural_hz < b.natural_hz; });
  return out;
}

Eigen::Vector4d HalfCarModel::undamped_frequencies_hz() const {
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat4> solver(K, M);
  Eigen::Vector4d f = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt() / (2.0 * std::numbers::pi);
  std::sort(f.data(), f.data() + 4);
  return f;
}

HalfCarModel::Mat8 HalfCarModel::paper_transform() const {
  Mat4 corners = Mat4::Zero();
  corners(0, 0) = 1.0;
  corners(0, 1) = lever_arm[0];
  corners(1, 2) = 1.0;
  corners(2, 0) = 1.0;
  corners(2, 1) = lever_arm[1];
  corners(3, 3) = 1.0;
  Mat8 t = Mat8::Zero();
  t.topRightCorner<4, 4>() = corners;    // velocities first
  t.bottomLeftCorner<4, 4>() = corners;  // then displacements
  return t;
}

}  // namespace rigctl
