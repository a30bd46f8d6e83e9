// A continuous transfer function fitted to the measured plant FRF, for
// predicting a design's step response in time (margins come from the
// measurement itself, not from this model):
//   position(s) = N_y(x) / (x^i D(x)),  pressure(s) = N_p(x) / D(x),  x = s / w0
// (a common denominator: one plant; i = 1 for a plant that integrates, as
// the quarter car does, i = 0 for one that does not, as the pneumatic servo
// held by its bladders' hysteresis; both are tried), D = 1 + d_1 x + ...,
// fitted to the FRF with the sampling's half-period delay removed, by
// Sanathanan-Koerner iterations of Levy's linear least squares weighted by
// coherence (w0, the band's geometric centre, keeps the powers of x of one
// size). The lowest order of D that fits within 0.5 dB rms and is stable is
// kept (else the best); the model is then discretised with the DAC's zero-order hold, so it
// samples as the loop does (tools/identify/plant_linearisation.hpp).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "tools/tune/loop_response.hpp"

namespace rigctl {

struct PlantModel {
  std::vector<double> d, n_position, n_pressure;  // D without its leading 1, numerators from x^0
  double w0 = 1.0;
  bool integrating = false;  // position has the extra 1 / x
  double rms_error_db = 0.0;  // of the position fit over the coherent points
  // Zero-order-hold discretisation: x_{k+1} = phi x_k + gamma u_k, y_k = c x_k
  // (row 0 position, row 1 pressure when fitted).
  Eigen::MatrixXd phi, gamma, c;
  bool has_pressure() const { return !n_pressure.empty(); }
};

PlantModel fit_plant(const PlantResponse& measured, double period_s);

// The continuous model's position FRF at f (for checks and plots).
Complex model_position(const PlantModel& m, double f_hz);

}  // namespace rigctl
