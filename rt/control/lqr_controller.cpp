#include "rt/control/lqr_controller.hpp"
#include "rt/control/lqr_design.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "plant/half_car/half_car_model.hpp"
#include "rt/control/lqr_riccati.hpp"

namespace rigctl {

LqrDesign design_half_car_lqr(const HalfCarParams& params, const LqrWeights& w) {
  for (double v : {w.heave_acceleration, w.angle_acceleration, w.suspension_travel, w.tyre_deflection, w.heave,
                   w.angle, w.force}) {
    if (!(v > 0.0)) throw std::invalid_argument("lqr: every weight scale must be positive");
  }
  namespace st = half_car_state;
  const HalfCarModel model = HalfCarModel::build(params);
  // Outputs y = Cy x + Dy f, each divided by its acceptable size.
  constexpr int kOut = 8;
  Eigen::Matrix<double, kOut, 8> cy = Eigen::Matrix<double, kOut, 8>::Zero();
  Eigen::Matrix<double, kOut, 2> dy = Eigen::Matrix<double, kOut, 2>::Zero();
  cy.row(0) = model.heave_acceleration_row() / w.heave_acceleration;
  dy.row(0) = model.heave_acceleration_feedthrough() / w.heave_acceleration;
  cy.row(1) = model.angle_acceleration_row() / w.angle_acceleration;
  dy.row(1) = model.angle_acceleration_feedthrough() / w.angle_acceleration;
  cy.row(2) = model.suspension_travel_row(0) / w.suspension_travel;
  cy.row(3) = model.suspension_travel_row(1) / w.suspension_travel;
  cy(4, st::kZu1) = 1.0 / w.tyre_deflection;
  cy(5, st::kZu2) = 1.0 / w.tyre_deflection;
  cy(6, st::kZs) = 1.0 / w.heave;
  cy(7, st::kPhi) = 1.0 / w.angle;

  // Scaling for conditioning: x = T xs, f = F fs.
  Eigen::Matrix<double, 8, 1> t;
  t << 0.01, 0.01, 0.01, 0.01, 0.1, 0.1, 0.5, 0.5;
  const Eigen::MatrixXd T = t.asDiagonal();
  const Eigen::MatrixXd Tinv = t.cwiseInverse().asDiagonal();
  const double fs = w.force;
  const Eigen::MatrixXd A = Tinv * model.A * T;
  const Eigen::MatrixXd B = Tinv * model.B * fs;
  const Eigen::MatrixXd C = cy * T;
  const Eigen::MatrixXd D = dy * fs;
  const Eigen::MatrixXd Q = C.transpose() * C;
  const Eigen::MatrixXd N = C.transpose() * D;
  const Eigen::MatrixXd R = D.transpose() * D + Eigen::MatrixXd::Identity(2, 2);  // (F_i / F)^2 in scaled units

  const CareSolution sol = solve_care(A, B, Q, R, N);
  LqrDesign design;
  design.K = fs * sol.K * Tinv;  // f = F fs = -F Ks T^-1 x
  design.residual = sol.residual;
  design.max_closed_loop_real = sol.max_closed_loop_real;
  Eigen::EigenSolver<Eigen::Matrix<double, 8, 8>> es(model.A - model.B * design.K, false);
  for (int i = 0; i < 8; ++i) {
    const auto l = es.eigenvalues()(i);
    design.closed_loop_damping(i) = -l.real() / std::abs(l);
  }
  return design;
}

LqrConfig LqrConfig::from_design(const HalfCarParams& params, const LqrWeights& weights, double force_limit) {
  const LqrDesign d = design_half_car_lqr(params, weights);
  LqrConfig c;
  for (int r = 0; r < 2; ++r) {
    for (int j = 0; j < 8; ++j) c.gain[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)] = d.K(r, j);
  }
  c.force_limit = force_limit;
  return c;
}

LqrController::LqrController(const LqrConfig& config) : config_(config) {
  if (!(config.force_limit > 0.0)) throw std::invalid_argument("lqr: force limit must be positive");
  for (const auto& row : config.gain) {
    for (double k : row) {
      if (!std::isfinite(k)) throw std::invalid_argument("lqr: gains must be finite");
    }
  }
}

void LqrController::update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept {
  const auto& ch = config_.channels;
  const std::array<double, 8> x = {sample_at(sample, ch.z_s) - setpoint, sample_at(sample, ch.phi),
                                   sample_at(sample, ch.z_u1),           sample_at(sample, ch.z_u2),
                                   sample_at(sample, ch.z_s_dot),        sample_at(sample, ch.phi_dot),
                                   sample_at(sample, ch.z_u1_dot),       sample_at(sample, ch.z_u2_dot)};
  std::array<double, 2> raw{}, force{};
  for (std::size_t r = 0; r < 2; ++r) {
    const auto& k = config_.gain[r];
    const double body = -(k[0] * x[0] + k[1] * x[1] + k[4] * x[4] + k[5] * x[5]);
    const double wheel = -(k[2] * x[2] + k[3] * x[3] + k[6] * x[6] + k[7] * x[7]);
    raw[r] = body + wheel;
    force[r] = std::clamp(raw[r], -config_.force_limit, config_.force_limit);
    terms.term[2 + 2 * r] = body;
    terms.term[3 + 2 * r] = wheel;
  }
  write_forces(command, ch, force[0], force[1]);
  terms.term[0] = force[0];
  terms.term[1] = force[1];
  fill_suspension_terms(terms, setpoint, sample, ch, raw, force);
}

}  // namespace rigctl
