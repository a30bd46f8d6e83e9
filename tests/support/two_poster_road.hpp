// A road as both posts of a two-poster rig see it, for the MIMO iteration
// tests: 20 s at 400 Hz, 0.5-20 Hz with a 1/f^2 displacement spectrum, the
// rear post the front's road 0.134 s later (wheelbase 2.68 m at 20 m/s) at
// 70 % plus 30 % of its own (the other wheel track), both ends tapered over
// 1 s. The targets are what a rig does on it.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "tools/iterate/spectrum.hpp"

namespace rigctl::test {

inline std::vector<std::vector<double>> two_poster_road(double front_rms_m, double period_s = 0.0025) {
  const std::size_t n = 8000;
  std::mt19937_64 rng(21);
  std::normal_distribution<double> normal;
  auto road = [&] {
    std::vector<double> w(n);
    for (double& v : w) v = normal(rng);
    Spectrum s = forward_fft(w);
    for (std::size_t k = 0; k < n; ++k) {
      const double f = bin_frequency_hz(k, n, period_s);
      s[k] *= (f < 0.5 || f > 20.0) ? 0.0 : 1.0 / (f * f);
    }
    return inverse_fft(s);
  };
  const auto front = road(), side = road();
  double rms = 0.0;
  for (double v : front) rms += v * v;
  const double scale = front_rms_m / std::sqrt(rms / static_cast<double>(n));
  const auto delay = static_cast<std::size_t>(std::lround(0.134 / period_s));
  std::vector<std::vector<double>> drives(2, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double taper = std::min({1.0, i / 400.0, (n - 1 - i) / 400.0});
    drives[0][i] = scale * taper * front[i];
    drives[1][i] = scale * taper * (0.7 * (i >= delay ? front[i - delay] : 0.0) + 0.3 * side[i]);
  }
  return drives;
}

}  // namespace rigctl::test
