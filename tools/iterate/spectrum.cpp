#include "tools/iterate/spectrum.hpp"

#include <cmath>
#include <numbers>

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

std::vector<double> smoothly_padded(const std::vector<double>& x, std::size_t pad) {
  std::vector<double> out(x);
  if (x.empty()) return out;
  out.reserve(x.size() + pad);
  const double from = x.back(), to = x.front();
  for (std::size_t i = 1; i <= pad; ++i) {
    const double w = 0.5 - 0.5 * std::cos(std::numbers::pi * static_cast<double>(i) / static_cast<double>(pad + 1));
    out.push_back(from + (to - from) * w);
  }
  return out;
}

std::size_t smooth_pad_samples(double dt) { return static_cast<std::size_t>(std::llround(2.0 / dt)); }

std::vector<double> filtered(const std::vector<double>& x, double dt,
                             const std::function<std::complex<double>(double f_hz)>& response) {
  Spectrum s = forward_fft(smoothly_padded(x, smooth_pad_samples(dt)));
  const std::size_t n = s.size();
  for (std::size_t k = 0; k <= n / 2; ++k) {
    const std::complex<double> h = response(bin_frequency_hz(k, n, dt));
    s[k] *= h;
    if (k > 0 && n - k != k) s[n - k] *= std::conj(h);
  }
  std::vector<double> out = inverse_fft(s);
  out.resize(x.size());
  return out;
}

std::vector<double> band_passed(const std::vector<double>& x, double dt, double low_hz, double high_hz) {
  return filtered(x, dt, [&](double f) { return std::complex<double>(f > 0.0 && f >= low_hz && f <= high_hz ? 1.0 : 0.0); });
}

}  // namespace rigctl
