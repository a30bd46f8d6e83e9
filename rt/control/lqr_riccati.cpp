#include "rt/control/lqr_riccati.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rigctl {

namespace {

using Eigen::MatrixXd;

double max_real_eigenvalue(const MatrixXd& a) {
  Eigen::EigenSolver<MatrixXd> es(a, false);
  return es.eigenvalues().real().maxCoeff();
}

double riccati_residual(const MatrixXd& a, const MatrixXd& g, const MatrixXd& q, const MatrixXd& p) {
  const MatrixXd atp = a.transpose() * p;
  const MatrixXd pgp = p * g * p;
  const MatrixXd r = atp + atp.transpose() - pgp + q;
  const double scale = q.norm() + 2.0 * atp.norm() + pgp.norm();
  return scale > 0.0 ? r.norm() / scale : r.norm();
}

}  // namespace

MatrixXd solve_lyapunov(const MatrixXd& A, const MatrixXd& Q) {
  const Eigen::Index n = A.rows();
  if (A.cols() != n || Q.rows() != n || Q.cols() != n) throw std::invalid_argument("lyapunov: sizes differ");
  // vec(A'X + XA) = (I (x) A' + A' (x) I) vec(X), column-major vec.
  const MatrixXd at = A.transpose();
  MatrixXd L = MatrixXd::Zero(n * n, n * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    L.block(i * n, i * n, n, n) += at;  // I (x) A'
    for (Eigen::Index j = 0; j < n; ++j) {
      L.block(i * n, j * n, n, n).diagonal().array() += at(i, j);  // A' (x) I
    }
  }
  const Eigen::VectorXd rhs = -Eigen::Map<const Eigen::VectorXd>(Q.data(), n * n);
  const Eigen::VectorXd x = L.fullPivLu().solve(rhs);
  MatrixXd X = Eigen::Map<const MatrixXd>(x.data(), n, n);
  return 0.5 * (X + X.transpose());
}

CareSolution solve_care(const MatrixXd& A, const MatrixXd& B, const MatrixXd& Q, const MatrixXd& R,
                        const MatrixXd& N_in, double tolerance) {
  const Eigen::Index n = A.rows(), m = B.cols();
  if (A.cols() != n || B.rows() != n || Q.rows() != n || Q.cols() != n || R.rows() != m || R.cols() != m) {
    throw std::invalid_argument("care: matrix sizes are inconsistent");
  }
  const MatrixXd N = N_in.size() == 0 ? MatrixXd::Zero(n, m) : N_in;
  if (N.rows() != n || N.cols() != m) throw std::invalid_argument("care: N must be n x m");
  const MatrixXd Rs = 0.5 * (R + R.transpose());
  Eigen::LLT<MatrixXd> r_llt(Rs);
  if (r_llt.info() != Eigen::Success) throw std::invalid_argument("care: R must be positive definite");

  const MatrixXd a = A - B * r_llt.solve(N.transpose());
  MatrixXd q = Q - N * r_llt.solve(N.transpose());
  q = 0.5 * (q + q.transpose());
  const MatrixXd g = B * r_llt.solve(B.transpose());

  CareSolution out;
  // Matrix sign function of the Hamiltonian.
  MatrixXd H(2 * n, 2 * n);
  H << a, -g, -q, -a.transpose();
  MatrixXd Z = H;
  const double dim = static_cast<double>(2 * n);
  for (int it = 0; it < 100; ++it) {
    Eigen::PartialPivLU<MatrixXd> lu(Z);
    double log_det = 0.0;
    const MatrixXd& lu_m = lu.matrixLU();
    for (Eigen::Index i = 0; i < lu_m.rows(); ++i) log_det += std::log(std::abs(lu_m(i, i)));
    if (!std::isfinite(log_det)) throw std::runtime_error("care: Hamiltonian has eigenvalues on the imaginary axis");
    const double c = std::exp(-log_det / dim);
    const MatrixXd next = 0.5 * (c * Z + lu.inverse() / c);
    const double change = (next - Z).norm() / next.norm();
    Z = next;
    out.sign_iterations = it + 1;
    if (change < 1e-13) break;
  }
  const MatrixXd w11 = Z.topLeftCorner(n, n), w12 = Z.topRightCorner(n, n);
  const MatrixXd w21 = Z.bottomLeftCorner(n, n), w22 = Z.bottomRightCorner(n, n);
  MatrixXd lhs(2 * n, n), rhs(2 * n, n);
  lhs << w12, w22 + MatrixXd::Identity(n, n);
  rhs << w11 + MatrixXd::Identity(n, n), w21;
  MatrixXd P = lhs.colPivHouseholderQr().solve(-rhs);
  P = 0.5 * (P + P.transpose());

  // Newton-Kleinman refinement from the sign-function solution.
  for (int it = 0; it < 50; ++it) {
    const MatrixXd k = r_llt.solve(B.transpose() * P);
    const MatrixXd ak = a - B * k;
    if (max_real_eigenvalue(ak) >= 0.0) break;  // not stabilising: keep what we have, checked below
    const MatrixXd next = solve_lyapunov(ak, q + k.transpose() * Rs * k);
    const double change = (next - P).norm() / std::max(next.norm(), 1e-300);
    P = next;
    out.newton_iterations = it + 1;
    if (change < 1e-14) break;
  }
  out.P = P;
  out.K = r_llt.solve(B.transpose() * P + N.transpose());
  out.residual = riccati_residual(a, g, q, P);
  out.max_closed_loop_real = max_real_eigenvalue(A - B * out.K);
  if (!(out.residual <= tolerance)) {
    throw std::runtime_error("care: residual " + std::to_string(out.residual) + " above tolerance");
  }
  if (!(out.max_closed_loop_real < 0.0)) throw std::runtime_error("care: closed loop is not stable");
  return out;
}

}  // namespace rigctl
