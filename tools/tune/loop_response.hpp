// The loop as the controller closes it, from the measured plant FRF: each
// path of the controller in its discrete form (the code in rt/control/
// written as transfer functions in z = exp(j w Ts)), and the position loop
// broken at the error, L = C_demand G / (1 + inner), where the inner loop is
// what feeds back besides the position error (P+V+dP: Kv omega and Kp dp;
// PI: nothing). The closed loop demand -> position is L / (1 + L), so L is
// also T / (1 - T) of a measured closed-loop FRF. The inner loop must be
// stable and robust on its own: its margins are checked too.
#pragma once

#include <complex>
#include <vector>

#include "tools/identify/frf_data.hpp"
#include "tools/tune/margins.hpp"
#include "tools/tune/loop_gains.hpp"

namespace rigctl {

using Complex = std::complex<double>;

// The plant FRFs the controller needs, on one frequency grid.
struct PlantResponse {
  std::vector<double> frequency_hz;
  std::vector<Complex> position;   // command -> controlled position (x_r, theta)
  std::vector<Complex> pressure;   // command -> differential pressure (P+V+dP only)
  std::vector<double> coherence;   // the worst of the channels used, lowered by their distortion (1 - ratio)

  static PlantResponse from_frf(const FrfData& frf);
};

// Controller paths at one frequency: u = demand_path r - feedback on y.
Complex pi_path(const LoopGains& g, double f_hz);                 // kp + ki Ts / (1 - z^-1)
Complex velocity_estimate(const LoopGains& g, double f_hz);       // omega / theta of the P+V+dP's filtered difference
Complex pressure_path(const LoopGains& g, double f_hz);           // 1, or the high-pass of eq. 18

// The position loop on the plant's frequencies.
std::vector<Complex> loop_transfer(const LoopGains& g, const PlantResponse& plant);
Complex loop_transfer_at(const LoopGains& g, double f_hz, Complex position, Complex pressure);
// The inner loop at the plant input (0 for PI).
Complex inner_loop_at(const LoopGains& g, double f_hz, Complex position, Complex pressure);
// The position loop measured from a closed-loop FRF: T / (1 - T).
std::vector<Complex> loop_from_closed_loop(const std::vector<Complex>& t);
// Its margins on the closed loop's coherent lines (no plant estimate and no
// controller model in between).
Margins closed_loop_margins(const FrfData& frf);

}  // namespace rigctl
