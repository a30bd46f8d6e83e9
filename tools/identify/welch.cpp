#include "tools/identify/welch.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <unsupported/Eigen/FFT>

namespace rigctl {

namespace {

std::vector<double> window_of(SpectralWindow w, std::size_t n) {
  std::vector<double> out(n, 1.0);
  if (w == SpectralWindow::kHann) {
    // Periodic Hann: with half overlap the windows sum to a constant.
    for (std::size_t i = 0; i < n; ++i) {
      out[i] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n));
    }
  }
  return out;
}

}  // namespace

CrossSpectra welch(const std::vector<std::span<const double>>& signals, const WelchSettings& s) {
  if (signals.empty()) throw std::invalid_argument("welch: no signals");
  const std::size_t length = signals.front().size();
  for (const auto& x : signals) {
    if (x.size() != length) throw std::invalid_argument("welch: signals of different lengths");
  }
  if (s.segment < 8 || s.step == 0 || length < s.segment) {
    throw std::invalid_argument("welch: the record (" + std::to_string(length) + " samples) is shorter than one segment (" +
                                std::to_string(s.segment) + ")");
  }
  const auto n = static_cast<int>(signals.size());
  const std::size_t bins = s.segment / 2 + 1;
  const auto w = window_of(s.window, s.segment);
  double w2 = 0.0;
  for (double v : w) w2 += v * v;

  CrossSpectra out;
  out.pairs.assign(bins, Eigen::MatrixXcd::Zero(n, n));
  for (std::size_t k = 0; k < bins; ++k) out.frequency_hz.push_back(static_cast<double>(k) * s.sample_rate_hz / static_cast<double>(s.segment));

  Eigen::FFT<double> fft;
  std::vector<double> segment(s.segment);
  std::vector<std::complex<double>> spectrum;
  Eigen::MatrixXcd x(n, static_cast<Eigen::Index>(bins));
  for (std::size_t start = 0; start + s.segment <= length; start += s.step) {
    for (int i = 0; i < n; ++i) {
      const auto& sig = signals[static_cast<std::size_t>(i)];
      double mean = 0.0;
      for (std::size_t j = 0; j < s.segment; ++j) mean += sig[start + j];
      mean /= static_cast<double>(s.segment);
      for (std::size_t j = 0; j < s.segment; ++j) segment[j] = (sig[start + j] - mean) * w[j];
      fft.fwd(spectrum, segment);
      for (std::size_t k = 0; k < bins; ++k) x(i, static_cast<Eigen::Index>(k)) = spectrum[k];
    }
    for (std::size_t k = 0; k < bins; ++k) {
      const auto col = x.col(static_cast<Eigen::Index>(k));
      out.pairs[k] += col.conjugate() * col.transpose();
    }
    ++out.averages;
  }
  for (std::size_t k = 0; k < bins; ++k) {
    const bool edge = k == 0 || (s.segment % 2 == 0 && k == bins - 1);
    out.pairs[k] *= (edge ? 1.0 : 2.0) / (s.sample_rate_hz * w2 * out.averages);
  }
  return out;
}

}  // namespace rigctl
