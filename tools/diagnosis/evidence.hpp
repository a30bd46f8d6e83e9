// What the residual shows (docs/diagnosis.md 3): conditional statistics on a
// cause's indicator, the signature each cause predicts, the noise floor of a
// channel and the frequency band of a residual. Pure functions of series.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace rigctl::diag {

// Share of the residual's variance over [b, end) explained by its mean in 20
// quantile bins of the indicator.
double binned_r2(const std::vector<double>& indicator, const std::vector<double>& e, std::size_t b, std::size_t end);

// The cause's signature as read from the residual `e` of the model without
// the effect, on its indicator, over [b, end): a sentence with numbers.
// `measured` and `simulated` are the channel's series (for the phase of a delay).
std::string signature(const std::string& cause, const std::string& indicator_name, const std::vector<double>& indicator,
                      const std::vector<double>& e, const std::vector<double>& measured,
                      const std::vector<double>& simulated, double dt, std::size_t b, std::size_t end);

// Noise floor of a measured channel: the white part of its sample-to-sample
// variation (second differences), never below its quantisation step's.
double noise_floor(const std::vector<double>& y);

struct Band {
  double lo_hz = 0.0, hi_hz = 0.0, peak_hz = 0.0;  // 10 % and 90 % of the power, and the largest bin
};
// Where the power of `e` over [b, end) lies (a log-spaced DFT from 1 / length to Nyquist).
Band power_band(const std::vector<double>& e, double dt, std::size_t b, std::size_t end);

}  // namespace rigctl::diag
