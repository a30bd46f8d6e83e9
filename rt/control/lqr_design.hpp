// The LQR gain design for the half car (rt/control/lqr_controller.hpp has the
// cost and the controller): the Riccati solution's gain with its checks.
// Apart from the controller's header so that Eigen stays out of the
// translation units that only read configs.
#pragma once

#include <Eigen/Dense>

#include "plant/half_car/half_car_params.hpp"
#include "rt/control/lqr_controller.hpp"

namespace rigctl {

struct LqrDesign {
  Eigen::Matrix<double, 2, 8> K = Eigen::Matrix<double, 2, 8>::Zero();
  double residual = 0.0;              // relative Riccati residual
  double max_closed_loop_real = 0.0;  // [1/s]
  Eigen::Matrix<double, 8, 1> closed_loop_damping = Eigen::Matrix<double, 8, 1>::Zero();  // per eigenvalue
};

// Designs K for the model of `params` (states scaled to typical magnitudes
// and forces to the force weight before solving, for conditioning).
LqrDesign design_half_car_lqr(const HalfCarParams& params, const LqrWeights& weights);

}  // namespace rigctl
