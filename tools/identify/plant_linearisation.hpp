// The simulated plant's own linear model about an operating point, for
// checking a measured FRF against the truth: the plant's derivative function
// (the very code the simulation integrates) differentiated by central
// differences at the equilibrium that holds the feedback at the operating
// point, discretised with the DAC's zero-order hold and evaluated as the
// loop samples it (a command written at tick k acts over the next period and
// is first seen in the sample of tick k + 1).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "config/rig_config.hpp"
#include "tools/identify/frf_data.hpp"

namespace rigctl {

struct LinearPlant {
  Eigen::MatrixXd a, b, c;          // dx/dt = A x + B u, y = C x
  std::vector<std::string> outputs; // one per row of C
  double command = 0.0;             // the command that holds the equilibrium
};

// The quarter car about the rod at x_r [m] (the body's bearing held, as it
// is under small motion). Outputs by run-file name: x_r, x_w, x_b, p1, p2.
LinearPlant linearise_quarter_car(const QuarterCarParams& params, double x_r, const std::vector<std::string>& outputs);

// The rig's plant linearised at `operating_point` for the given responses;
// empty when the rig kind has no linearisation (documented per kind).
std::vector<FrfCurve> linearised_plant_frf(const RigConfig& config, double operating_point,
                                           const std::vector<std::string>& responses,
                                           const std::vector<double>& frequency_hz);

// C (zI - Phi)^-1 Gamma at z = exp(j 2 pi f T), Phi and Gamma the
// zero-order-hold discretisation of (A, B) over the period T.
std::vector<FrfCurve> sampled_frf(const LinearPlant& plant, double period_s, const std::vector<double>& frequency_hz);

}  // namespace rigctl
