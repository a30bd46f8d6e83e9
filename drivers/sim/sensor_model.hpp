// What a transducer and its ADC do to a true signal: offset, Gaussian noise,
// clipping to the range and quantisation to the converter's resolution.
#pragma once

#include <cmath>
#include <random>

namespace rigctl {

struct SensorSpec {
  double noise_sd = 0.0;  // [SI unit of the channel]
  int bits = 0;           // ADC resolution; 0 = not quantised
  double range_min = 0.0;  // [SI] ADC full scale; used when bits > 0
  double range_max = 0.0;
  double offset = 0.0;     // [SI] added to the true value
  // [s] transport delay of the transducer and its filter; the simulated
  // driver interpolates a history of the true signal (cubic, so that it is
  // not the linear interpolation the diagnosis fits). 0 = none.
  double delay_s = 0.0;
  // [Hz] cut-off of a second-order Butterworth conditioning filter on the
  // true signal (drivers/sim/conditioning_filter.hpp); 0 = none.
  double filter_hz = 0.0;
};

// A standard normal draw by Box-Muller, by hand: std::normal_distribution
// keeps hidden state and its output differs between standard libraries; this
// is the same everywhere, so a seed makes the same run on any machine.
inline double standard_normal(std::mt19937_64& rng) noexcept {
  constexpr double kTwoPi = 6.283185307179586;
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
}

class SensorModel {
 public:
  SensorModel() = default;
  explicit SensorModel(const SensorSpec& spec);
  // Allocation free; draws from the caller's generator so one seed makes the
  // whole run reproducible.
  double measure(double truth, std::mt19937_64& rng) const noexcept;
  double lsb() const noexcept { return lsb_; }
  double delay_s() const noexcept { return spec_.delay_s; }
  double filter_hz() const noexcept { return spec_.filter_hz; }

 private:
  SensorSpec spec_;
  double lsb_ = 0.0;
};

}  // namespace rigctl
