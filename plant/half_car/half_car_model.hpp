// The linear 4-DOF half vehicle of seed 001, eqs. 1-4, in the state-space
// form of eq. 5, built with Eigen. Used for eigenfrequencies and LQR design;
// the simulator (half_car_plant.hpp) integrates the same equations with the
// tyre made unilateral.
//
// Generalised coordinates q = [z_s, phi, z_u1, z_u2] (heave and angle at the
// centre of gravity, wheels), state x = [q; dq/dt]:
//   M q'' + C q' + K q = G f + K_r r + C_r r' + e_phi M_roll
//   dx/dt = A x + B f + E r + E_rate r' + e_roll M_roll        (eq. 5)
// with f = [F1, F2] the active forces, r = [z_r1, z_r2] the road (the
// paper's D is E here). Each corner i contributes its suspension
// deflection d_i = z_s + l_i phi - z_ui = g_i' q with g_1 = [1, l1, -1, 0],
// g_2 = [1, l2, 0, -1]:
//   K = sum_i k_i g_i g_i' + diag(0, 0, kt_1, kt_2),  C likewise,
//   G = [g_1 g_2]  (F_i lifts the body at l_i and pushes wheel i down).
// The paper writes eq. 5 in corner coordinates, y = [Z_sr', Z_ur', Z_sl',
// Z_ul', Z_sr, Z_ur, Z_sl, Z_ul]; paper_transform() maps x to y (y = T x), so
// A_paper = T A T^-1. Eq. 2 needs a = b = w/2 for corner coordinates to
// carry a diagonal mass matrix; the centre-of-gravity form holds for any a, b.
// (Two slips in the paper's equations are read as intended: the constraint
// is phi = (Z_sr - Z_sl)/w, and eq. 4's tyre term is K_u (Z_ul - Z_rl).)
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "plant/half_car/half_car_params.hpp"

namespace rigctl {

// State indices of x.
namespace half_car_state {
inline constexpr int kZs = 0, kPhi = 1, kZu1 = 2, kZu2 = 3, kVs = 4, kOmega = 5, kVu1 = 6, kVu2 = 7;
inline constexpr int kCount = 8;
}  // namespace half_car_state

enum class HalfCarDof : int { kHeave = 0, kAngle = 1, kWheel1 = 2, kWheel2 = 3 };

struct HalfCarMode {
  double natural_hz = 0.0;  // |lambda| / 2 pi
  double damped_hz = 0.0;   // Im(lambda) / 2 pi
  double damping_ratio = 0.0;
  HalfCarDof dominant = HalfCarDof::kHeave;  // coordinate with the largest kinetic-energy share
};

struct HalfCarModel {
  using Mat4 = Eigen::Matrix<double, 4, 4>;
  using Mat8 = Eigen::Matrix<double, 8, 8>;
  using Mat82 = Eigen::Matrix<double, 8, 2>;

  Mat4 M, C, K;
  Eigen::Matrix<double, 4, 2> G;  // active forces into the coordinates
  Mat8 A;
  Mat82 B;       // active forces [F1, F2]
  Mat82 E;       // road displacements [z_r1, z_r2]
  Mat82 E_rate;  // road rates (tyre damping; zero for the paper's tyre)
  Eigen::Matrix<double, 8, 1> e_roll;  // roll moment M_roll
  double lever_arm[2] = {0.0, 0.0};

  static HalfCarModel build(const HalfCarParams& p);

  // Rows of output matrices y = Cy x + Dy f for common outputs.
  Eigen::Matrix<double, 1, 8> heave_acceleration_row() const { return A.row(half_car_state::kVs); }
  Eigen::Matrix<double, 1, 2> heave_acceleration_feedthrough() const { return B.row(half_car_state::kVs); }
  Eigen::Matrix<double, 1, 8> angle_acceleration_row() const { return A.row(half_car_state::kOmega); }
  Eigen::Matrix<double, 1, 2> angle_acceleration_feedthrough() const { return B.row(half_car_state::kOmega); }
  // Suspension travel z_s + l_i phi - z_ui of corner i (positive: extended).
  Eigen::Matrix<double, 1, 8> suspension_travel_row(int wheel) const;

  // Damped modes from the eigenvalues of A, sorted by natural frequency
  // (complex pairs only; an overdamped mode has no frequency to report).
  std::vector<HalfCarMode> modes() const;
  // Undamped natural frequencies [Hz], ascending: sqrt of the generalised
  // eigenvalues of (K, M) / 2 pi.
  Eigen::Vector4d undamped_frequencies_hz() const;
  // y = T x in the paper's corner coordinates.
  Mat8 paper_transform() const;
};

}  // namespace rigctl
