// Continuous-time algebraic Riccati equation for LQR design (not real-time).
//
//   minimise  integral x'Q x + 2 x'N u + u'R u  dt,   dx/dt = A x + B u
//   A'P + P A - (P B + N) R^-1 (B'P + N') + Q = 0,   K = R^-1 (B'P + N'),  u = -K x
//
// Method: the cross term is removed (A_ = A - B R^-1 N', Q_ = Q - N R^-1 N'),
// the stabilising solution is found from the matrix sign function of the
// Hamiltonian H = [A_, -G; -Q_, -A_'] (G = B R^-1 B'; Newton iteration
// Z <- (c Z + (c Z)^-1)/2 with determinant scaling c = |det Z|^(-1/2n)),
// P solving [W12; W22 + I] P = -[W11 + I; W21] in least squares (W = sign H),
// and then refined by Newton-Kleinman steps (each a Lyapunov equation
// (A_ - B K)'P + P (A_ - B K) + Q_ + K'R K = 0, solved through its Kronecker
// form, fine for the n <= ~20 of suspension models). Eigen has no ordered
// Schur form, so the Laub/Schur method is not available; the sign function
// needs no stabilising initial gain, and Newton-Kleinman converges
// quadratically from its result. The answer is verified: the relative
// residual and the closed-loop eigenvalues are reported, and a solution whose
// closed loop is not stable or whose residual exceeds the tolerance throws.
#pragma once

#include <Eigen/Dense>

namespace rigctl {

struct CareSolution {
  Eigen::MatrixXd P;               // stabilising solution, symmetric
  Eigen::MatrixXd K;               // R^-1 (B'P + N')
  double residual = 0.0;           // ||Riccati(P)||_F / (||Q_|| + ||A_'P|| + ||P A_|| + ||P G P||)
  double max_closed_loop_real = 0.0;  // largest real part of eig(A - B K), < 0
  int sign_iterations = 0;
  int newton_iterations = 0;
};

// Solves A' X + X A + Q = 0 (A stable, Q symmetric) via the Kronecker form.
Eigen::MatrixXd solve_lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q);

// N may be empty (0 x 0) for no cross term. Throws std::invalid_argument on
// inconsistent sizes or R not positive definite, std::runtime_error when no
// stabilising solution to `tolerance` is found (e.g. (A, B) not
// stabilisable).
CareSolution solve_care(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                        const Eigen::MatrixXd& R, const Eigen::MatrixXd& N = Eigen::MatrixXd(),
                        double tolerance = 1e-9);

}  // namespace rigctl
