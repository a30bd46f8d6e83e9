#include "tools/iterate/resample.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rigctl {

namespace {

// The low-pass's cut-off as a share of the lower Nyquist frequency: the
// Hann-windowed sinc's transition band (about 2 / 16 of the cut-off wide)
// ends below the Nyquist frequency.
constexpr double kCutoffShare = 0.9;
// Zero crossings of the sinc on either side: a stop band near -60 dB.
constexpr double kZeroCrossings = 16.0;

double sinc(double x) { return x == 0.0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x); }

}  // namespace

std::vector<double> resample(const std::vector<double>& x, double from_s, double to_s) {
  if (std::abs(from_s - to_s) <= 1e-9 * to_s || x.size() < 2) return x;
  const double cutoff_hz = kCutoffShare * 0.5 / std::max(from_s, to_s);
  const double half_width_s = kZeroCrossings / (2.0 * cutoff_hz);
  const auto reach = static_cast<long>(std::ceil(half_width_s / from_s));
  const double span = static_cast<double>(x.size() - 1) * from_s;
  const auto count = static_cast<std::size_t>(std::floor(span / to_s + 1e-9)) + 1;
  const long last = static_cast<long>(x.size()) - 1;
  std::vector<double> out(count);
  for (std::size_t j = 0; j < count; ++j) {
    const double t = static_cast<double>(j) * to_s;
    const auto centre = static_cast<long>(std::floor(t / from_s));
    double sum = 0.0, weights = 0.0;
    for (long n = centre - reach; n <= centre + reach + 1; ++n) {
      const double tau = t - static_cast<double>(n) * from_s;
      if (std::abs(tau) >= half_width_s) continue;
      const double w = sinc(2.0 * cutoff_hz * tau) * (0.5 + 0.5 * std::cos(std::numbers::pi * tau / half_width_s));
      sum += w * x[static_cast<std::size_t>(std::clamp(n, 0L, last))];
      weights += w;
    }
    out[j] = sum / weights;
  }
  return out;
}

}  // namespace rigctl
