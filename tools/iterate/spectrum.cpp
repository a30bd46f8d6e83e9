#include "tools/iterate/spectrum.hpp"

#include <unsupported/Eigen/FFT>

namespace rigctl {

Spectrum forward_fft(const std::vector<double>& x) {
  Eigen::FFT<double> fft;
  Spectrum out;
  fft.fwd(out, x);  // full spectrum: Eigen fills the mirrored half too
  return out;
}

std::vector<double> inverse_fft(const Spectrum& x) {
  Eigen::FFT<double> fft;
  std::vector<double> out;
  fft.inv(out, x);
  return out;
}

double bin_frequency_hz(std::size_t k, std::size_t n, double dt) {
  const std::size_t folded = k <= n / 2 ? k : n - k;
  return static_cast<double>(folded) / (static_cast<double>(n) * dt);
}

std::vector<double> band_limited(const std::vector<double>& x, double dt, double low_hz, double high_hz) {
  Spectrum s = forward_fft(x);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double f = bin_frequency_hz(k, s.size(), dt);
    if (k == 0 || f < low_hz || f > high_hz) s[k] = 0.0;
  }
  return inverse_fft(s);
}

}  // namespace rigctl
