// Stability margins of a loop transfer sampled on a frequency grid (only
// what the grid covers: a crossing outside it is not seen): crossover where
// |L| falls through 1, the phase margin there, the gain margin at the first
// phase crossing of -180 degrees above it, and the peak of the sensitivity.
#pragma once

#include <complex>
#include <vector>

namespace rigctl {

struct Margins {
  double crossover_hz = 0.0;      // NaN: |L| does not fall through 1 in the band
  double phase_margin_deg = 0.0;  // NaN with the crossover
  double phase_crossover_hz = 0.0;  // NaN: none above the crossover in the band
  // No phase crossing above the crossover in the band: the bound -|L| at the
  // band's top, and beyond_band set (past the band the rigs' loops only fall,
  // so any later crossing has at least this margin).
  double gain_margin_db = 0.0;
  bool gain_margin_beyond_band = false;
  double peak_sensitivity = 0.0;  // max |1 / (1 + L)|
};

// The phase of L unwrapped along the grid, starting on the negative branch
// (a physical loop lags at low frequency) [deg].
std::vector<double> unwrapped_phase_deg(const std::vector<std::complex<double>>& l);

Margins loop_margins(const std::vector<double>& frequency_hz, const std::vector<std::complex<double>>& l);

}  // namespace rigctl
