// A discrete transfer function fitted to the measured plant FRF, for
// predicting the step response of a design in time (margins come from the
// measurement itself, not from this model):
//   position(z) = B_y(z^-1) / ((1 - z^-1) A(z^-1))      (the rigs' plants integrate)
//   pressure(z) = B_p(z^-1) / A(z^-1)
// with A = 1 + a_1 z^-1 + ... and every B starting at z^-1 (a command acts
// from the next sample on). Sanathanan-Koerner iterations of Levy's linear
// least squares, weighted by coherence; the lowest order of A that fits the
// coherent points within 1 dB rms (and is stable) is kept.
#pragma once

#include <vector>

#include "tools/tune/loop_response.hpp"

namespace rigctl {

struct PlantModel {
  std::vector<double> a;                    // A without its leading 1
  std::vector<double> b_position, b_pressure;
  double rms_error_db = 0.0;                // of the position fit over the coherent points
  bool has_pressure() const { return !b_pressure.empty(); }
};

PlantModel fit_plant(const PlantResponse& measured, double period_s);

// The model's FRF at f (for checks and plots).
Complex model_position(const PlantModel& m, double f_hz, double period_s);

}  // namespace rigctl
