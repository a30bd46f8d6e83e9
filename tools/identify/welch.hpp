// Welch's averaged cross-spectral estimate of several signals sampled
// together: segments (windowed, each one's mean removed) are transformed
// with Eigen's FFT and every pair's cross spectrum averaged over them.
// One-sided power spectral densities [unit_i unit_j / Hz].
#pragma once

#include <complex>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rigctl {

enum class SpectralWindow : uint8_t {
  kRectangular,  // periodic excitation averaged over whole periods: no leakage
  kHann,         // noise excitation: low leakage, half-overlapping segments
};

constexpr std::string_view to_string(SpectralWindow w) {
  switch (w) {
    case SpectralWindow::kRectangular: return "rectangular";
    case SpectralWindow::kHann: return "hann";
  }
  return "unknown";
}

struct WelchSettings {
  std::size_t segment = 1600;  // ticks per segment (the frequency resolution is sample_rate / segment)
  std::size_t step = 1600;     // ticks from one segment's start to the next (segment / 2: half overlap)
  SpectralWindow window = SpectralWindow::kRectangular;
  double sample_rate_hz = 400.0;
};

struct CrossSpectra {
  std::vector<double> frequency_hz;     // bin k at k sample_rate / segment, k = 0 .. segment / 2
  std::vector<Eigen::MatrixXcd> pairs;  // pairs[k](i, j) = E[conj(X_i) X_j], scaled to one-sided density
  int averages = 0;
  std::complex<double> at(std::size_t k, int i, int j) const { return pairs[k](i, j); }
  double power(std::size_t k, int i) const { return pairs[k](i, i).real(); }
};

// Every signal must have the same length, at least one segment. Throws
// std::invalid_argument otherwise.
CrossSpectra welch(const std::vector<std::span<const double>>& signals, const WelchSettings& settings);

}  // namespace rigctl
