// The loop as the controller closes it, from the measured plant FRF: each
// feedback path of the controller in its discrete form (the code in
// rt/control/ written as transfer functions in z = exp(j w Ts)), and the
// loop transfer broken at the plant input (the valve command), L = sum of
// path x plant, so that the closed loop's characteristic equation is 1 + L.
// For PI, L = C G is also the loop broken at the error: the two coincide.
#pragma once

#include <complex>
#include <vector>

#include "tools/identify/frf_data.hpp"
#include "tools/tune/loop_gains.hpp"

namespace rigctl {

using Complex = std::complex<double>;

// The plant FRFs the controller needs, on one frequency grid.
struct PlantResponse {
  std::vector<double> frequency_hz;
  std::vector<Complex> position;   // command -> controlled position (x_r, theta)
  std::vector<Complex> pressure;   // command -> differential pressure (P+V+dP only)
  std::vector<double> coherence;   // the worst of the channels used

  static PlantResponse from_frf(const FrfData& frf);
};

// Controller paths at one frequency: u = demand_path r - feedback on y.
Complex pi_path(const LoopGains& g, double f_hz);                 // kp + ki Ts / (1 - z^-1)
Complex velocity_estimate(const LoopGains& g, double f_hz);       // omega / theta of the P+V+dP's filtered difference
Complex pressure_path(const LoopGains& g, double f_hz);           // 1, or the high-pass of eq. 18

// The loop transfer at the plant input on the plant's frequencies.
std::vector<Complex> loop_transfer(const LoopGains& g, const PlantResponse& plant);
Complex loop_transfer_at(const LoopGains& g, double f_hz, Complex position, Complex pressure);

}  // namespace rigctl
