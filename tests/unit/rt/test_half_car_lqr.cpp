// The Riccati solver behind the half car's LQR controller: textbook cases
// with closed-form answers, the cross term, a problem with no solution, and
// the optimality of the half-car design (every perturbed gain costs more).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "plant/half_car/half_car_model.hpp"
#include "rt/control/lqr_controller.hpp"
#include "rt/control/lqr_design.hpp"
#include "rt/control/lqr_riccati.hpp"

using namespace rigctl;
using Eigen::MatrixXd;

TEST(HalfCarLqr, DoubleIntegratorHasTheClosedFormSolution) {
  MatrixXd A(2, 2), B(2, 1);
  A << 0, 1, 0, 0;
  B << 0, 1;
  const CareSolution s = solve_care(A, B, MatrixXd::Identity(2, 2), MatrixXd::Identity(1, 1));
  // P = [sqrt3 1; 1 sqrt3], K = [1 sqrt3].
  EXPECT_NEAR(s.P(0, 0), std::sqrt(3.0), 1e-10);
  EXPECT_NEAR(s.P(0, 1), 1.0, 1e-10);
  EXPECT_NEAR(s.P(1, 0), 1.0, 1e-10);
  EXPECT_NEAR(s.P(1, 1), std::sqrt(3.0), 1e-10);
  EXPECT_NEAR(s.K(0, 0), 1.0, 1e-10);
  EXPECT_NEAR(s.K(0, 1), std::sqrt(3.0), 1e-10);
  EXPECT_LT(s.residual, 1e-12);
  EXPECT_LT(s.max_closed_loop_real, 0.0);
}

TEST(HalfCarLqr, UnstablePlantNeedsNoStabilisingGuess) {
  // Scalar a = 1, b = 1, q = 1, r = 1: p^2 - 2p - 1 = 0, p = 1 + sqrt2.
  const MatrixXd one = MatrixXd::Identity(1, 1);
  const CareSolution s = solve_care(one, one, one, one);
  EXPECT_NEAR(s.P(0, 0), 1.0 + std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.max_closed_loop_real, -std::sqrt(2.0), 1e-12);
}

TEST(HalfCarLqr, CrossTermEqualsTheTransformedProblem) {
  MatrixXd A(3, 3), B(3, 2), Q(3, 3), R(2, 2), N(3, 2);
  A << 0, 1, 0, -2, -0.3, 1, 0.5, 0, -1;
  B << 0, 0, 1, 0.2, 0, 1;
  MatrixXd C(4, 3), D(4, 2);
  C << 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, -1, 0.5;
  D << 0, 0, 0, 0, 0, 0, 0.7, -0.2;
  Q = C.transpose() * C;
  N = C.transpose() * D;
  R = D.transpose() * D + MatrixXd::Identity(2, 2) * 0.1;
  const CareSolution with = solve_care(A, B, Q, R, N);
  const MatrixXd Ri = R.inverse();
  const CareSolution without = solve_care(A - B * Ri * N.transpose(), B, Q - N * Ri * N.transpose(), R);
  EXPECT_LT((with.P - without.P).norm(), 1e-9 * with.P.norm());
  EXPECT_LT((with.K - (without.K + Ri * N.transpose())).norm(), 1e-9 * with.K.norm());
  // The full Riccati equation with the cross term holds.
  const MatrixXd res = A.transpose() * with.P + with.P * A -
                       (with.P * B + N) * Ri * (B.transpose() * with.P + N.transpose()) + Q;
  EXPECT_LT(res.norm(), 1e-9 * Q.norm());
}

TEST(HalfCarLqr, UnstabilisablePlantIsRefused) {
  MatrixXd A(2, 2), B(2, 1);
  A << 1, 0, 0, -1;
  B << 0, 1;  // the unstable mode is not reachable
  EXPECT_THROW(solve_care(A, B, MatrixXd::Identity(2, 2), MatrixXd::Identity(1, 1)), std::runtime_error);
  EXPECT_THROW(solve_care(A, B, MatrixXd::Identity(2, 2), -MatrixXd::Identity(1, 1)), std::invalid_argument);
}

TEST(HalfCarLqr, LyapunovSolverSatisfiesItsEquation) {
  MatrixXd A(3, 3), Q(3, 3);
  A << -1, 2, 0, -3, -1, 1, 0, 0.5, -2;
  Q << 2, 0.1, 0, 0.1, 1, 0.3, 0, 0.3, 4;
  const MatrixXd X = solve_lyapunov(A, Q);
  EXPECT_LT((A.transpose() * X + X * A + Q).norm(), 1e-12);
}

TEST(HalfCarLqr, HalfCarDesignIsStableAndOptimal) {
  const HalfCarParams p;
  const LqrWeights w;
  const LqrDesign d = design_half_car_lqr(p, w);
  std::printf("LQR residual %.2e, slowest closed-loop pole %.2f 1/s, least damping %.3f\nK =\n", d.residual,
              d.max_closed_loop_real, d.closed_loop_damping.minCoeff());
  for (int r = 0; r < 2; ++r) {
    for (int j = 0; j < 8; ++j) std::printf("%11.1f", d.K(r, j));
    std::printf("\n");
  }
  EXPECT_LT(d.residual, 1e-10);
  EXPECT_LT(d.max_closed_loop_real, 0.0);

  // Cost of a gain from a unit initial state in every direction,
  // trace(P_K) with (A - BK)'P_K + P_K (A - BK) + Q - N K - K'N' + K'R K = 0,
  // built here from the model and the weights, independently of the design's
  // scaling: the designed K must beat every perturbed one.
  const HalfCarModel m = HalfCarModel::build(p);
  Eigen::Matrix<double, 8, 8> cy = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 2> dy = Eigen::Matrix<double, 8, 2>::Zero();
  cy.row(0) = m.heave_acceleration_row() / w.heave_acceleration;
  dy.row(0) = m.heave_acceleration_feedthrough() / w.heave_acceleration;
  cy.row(1) = m.angle_acceleration_row() / w.angle_acceleration;
  dy.row(1) = m.angle_acceleration_feedthrough() / w.angle_acceleration;
  cy.row(2) = m.suspension_travel_row(0) / w.suspension_travel;
  cy.row(3) = m.suspension_travel_row(1) / w.suspension_travel;
  cy(4, half_car_state::kZu1) = 1.0 / w.tyre_deflection;
  cy(5, half_car_state::kZu2) = 1.0 / w.tyre_deflection;
  cy(6, half_car_state::kZs) = 1.0 / w.heave;
  cy(7, half_car_state::kPhi) = 1.0 / w.angle;
  const MatrixXd Q = cy.transpose() * cy, N = cy.transpose() * dy;
  const MatrixXd R = dy.transpose() * dy + MatrixXd::Identity(2, 2) / (w.force * w.force);
  // Weight the initial states by their typical sizes so every direction counts.
  Eigen::Matrix<double, 8, 1> x0;
  x0 << 0.01, 0.01, 0.01, 0.01, 0.1, 0.1, 0.5, 0.5;
  auto cost = [&](const MatrixXd& K) -> double {
    const MatrixXd acl = MatrixXd(m.A) - MatrixXd(m.B) * K;
    Eigen::EigenSolver<MatrixXd> es(acl, false);
    if (es.eigenvalues().real().maxCoeff() >= 0.0) return HUGE_VAL;
    const MatrixXd qk = Q - N * K - K.transpose() * N.transpose() + K.transpose() * R * K;
    const MatrixXd pk = solve_lyapunov(acl, qk);
    return (x0.asDiagonal() * pk * x0.asDiagonal()).trace();
  };
  const MatrixXd K = d.K;
  const double best = cost(K);
  for (int r = 0; r < 2; ++r) {
    for (int j = 0; j < 8; ++j) {
      for (double f : {0.9, 1.1}) {
        MatrixXd Kp = K;
        Kp(r, j) *= f;
        EXPECT_GT(cost(Kp), best) << "K(" << r << "," << j << ") x " << f;
      }
    }
  }
  EXPECT_GT(cost(MatrixXd::Zero(2, 8)), best);  // passive costs more
}
