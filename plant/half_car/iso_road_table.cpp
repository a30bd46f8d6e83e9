#include "plant/half_car/iso_road_table.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <stdexcept>

#include <unsupported/Eigen/FFT>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kN0 = 0.1;           // ISO 8608 reference spatial frequency [cycle/m]
constexpr double kPointsPerWave = 8;  // grid points per shortest wave (see the header)

// Uniform in [0, 1) from the raw 64-bit output: identical on every standard
// library (std::uniform_real_distribution is not).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

std::size_t power_of_two_at_least(double n) {
  std::size_t p = 1;
  while (static_cast<double>(p) < n) p <<= 1;
  return p;
}

}  // namespace

IsoRoadTable::IsoRoadTable(const IsoRoadTableSpec& spec) {
  if (!(spec.n_min > 0.0) || !(spec.n_max > spec.n_min)) throw std::invalid_argument("road: ISO band needs 0 < n_min < n_max");
  if (!(spec.gd_n0 >= 0.0)) throw std::invalid_argument("road: Gd(n0) must not be negative");
  if (spec.tracks < 1) throw std::invalid_argument("road: at least one track");
  if (!(spec.min_length * spec.n_min >= 1.0)) {
    throw std::invalid_argument("road: the track length must hold the longest wave (length >= 1 / n_min)");
  }
  step_ = 1.0 / (kPointsPerWave * spec.n_max);
  points_ = power_of_two_at_least(spec.min_length / step_);
  if (points_ > (std::size_t{1} << 24)) throw std::invalid_argument("road: the track would need over 16 M grid points");
  generate(spec);
}

void IsoRoadTable::generate(const IsoRoadTableSpec& spec) {
  const std::size_t n = points_;
  const double length = this->length();
  const auto k_lo = static_cast<std::size_t>(std::ceil(spec.n_min * length));
  const auto k_hi = static_cast<std::size_t>(std::floor(spec.n_max * length));  // < n / 2 by the choice of step
  std::mt19937_64 rng(spec.seed);
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::Unscaled);
  std::vector<std::complex<double>> spectrum(n), out(n);
  variance_ = 0.0;
  for (int t = 0; t < spec.tracks; ++t) {
    // Height and slope in one inverse FFT: both spectra are Hermitian, so
    // the transform of (height + i slope) is height + i slope sample by sample.
    std::fill(spectrum.begin(), spectrum.end(), std::complex<double>{});
    double track_variance = 0.0;
    for (std::size_t k = k_lo; k <= k_hi; ++k) {
      const double freq = static_cast<double>(k) / length;
      const double bin_variance = spec.gd_n0 * (kN0 / freq) * (kN0 / freq) / length;  // Gd(n_k) dn
      const double amplitude = std::sqrt(2.0 * bin_variance);
      const std::complex<double> half = std::polar(0.5 * amplitude, kTwoPi * uniform01(rng));
      const double w = kTwoPi * freq;
      spectrum[k] = half * (1.0 - w);              // c + i (i w c)
      spectrum[n - k] = std::conj(half) * (1.0 + w);  // conj(c) + i conj(i w c)
      track_variance += bin_variance;
    }
    fft.inv(out, spectrum);
    std::vector<Knot> knots(n);
    for (std::size_t j = 0; j < n; ++j) {
      knots[j] = {static_cast<float>(out[j].real()), static_cast<float>(out[j].imag() * step_)};
    }
    tracks_.push_back(std::move(knots));
    variance_ = track_variance;  // every track has the same bins
  }
}

IsoRoadTable::Point IsoRoadTable::at(int track, double x) const noexcept {
  const auto& knots = tracks_[static_cast<std::size_t>(track)];
  const double u = x / step_;
  const double cell = std::floor(u);
  const double s = u - cell;
  const std::size_t mask = points_ - 1;
  const auto i = static_cast<std::size_t>(static_cast<int64_t>(cell)) & mask;  // two's complement wraps negatives
  const Knot& a = knots[i];
  const Knot& b = knots[(i + 1) & mask];
  // Cubic Hermite on [0, 1] with end slopes a.slope_step, b.slope_step.
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  const double z = h00 * a.z + h10 * a.slope_step + h01 * b.z + h11 * b.slope_step;
  const double dh00 = 6 * s2 - 6 * s, dh10 = 3 * s2 - 4 * s + 1, dh01 = -dh00, dh11 = 3 * s2 - 2 * s;
  const double dz_du = dh00 * a.z + dh10 * a.slope_step + dh01 * b.z + dh11 * b.slope_step;
  return {z, dz_du / step_};
}

}  // namespace rigctl
