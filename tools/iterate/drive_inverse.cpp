#include "tools/iterate/drive_inverse.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

GainBands gain_bands(double band_min_hz, double band_max_hz) {
  GainBands b;
  b.edges_hz.push_back(0.0);
  for (double f = band_min_hz; f < band_max_hz; f *= std::cbrt(2.0)) b.edges_hz.push_back(f);
  b.edges_hz.push_back(band_max_hz + 1e-9);
  return b;
}

std::size_t GainBands::band_of(double f) const {
  const auto it = std::upper_bound(edges_hz.begin(), edges_hz.end(), f);
  if (it == edges_hz.begin() || it == edges_hz.end()) return size();
  return static_cast<std::size_t>(it - edges_hz.begin()) - 1;
}

DriveInverse::DriveInverse(const DriveFrf& frf, std::size_t samples, double period_s, const InverseSettings& s)
    : samples_(samples),
      padded_(samples + static_cast<std::size_t>(std::llround(s.pad_s / period_s))),
      period_s_(period_s),
      bands_(gain_bands(s.band_min_hz, s.band_max_hz)) {
  double largest = 0.0;
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    if (frf.frequency_hz[i] <= s.band_max_hz) largest = std::max(largest, std::abs(frf.value[i]));
  }
  const double eps2 = std::pow(s.regularisation * largest, 2);
  inverse_.assign(padded_, 0.0);
  band_.assign(padded_, bands_.size());
  for (std::size_t k = 0; k < padded_; ++k) {
    const double f = bin_frequency_hz(k, padded_, period_s);
    if (f > s.band_max_hz) continue;
    band_[k] = bands_.band_of(f);
    if (frf.coherence_at(f) < s.coherence_gate) {
      if (k <= padded_ / 2) ++gated_;
      continue;
    }
    std::complex<double> h = frf.at(f);
    if (k > padded_ / 2) h = std::conj(h);  // the mirrored half of a real record
    inverse_[k] = std::conj(h) / (std::norm(h) + eps2);
  }
}

// The record continued smoothly from its end back to its start (no step for
// the FFT's periodic view to see: a target from home to mid-stroke would
// otherwise put a spike at both ends of the drive).
std::vector<double> DriveInverse::padded_record(const std::vector<double>& x) const {
  std::vector<double> head(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(std::min(x.size(), samples_)));
  head.resize(samples_, head.empty() ? 0.0 : head.back());
  return smoothly_padded(head, padded_ - samples_);
}

std::vector<double> DriveInverse::apply(const std::vector<double>& x, const std::vector<double>& gain) const {
  const std::vector<double> padded = padded_record(x);
  Spectrum s = forward_fft(padded);
  for (std::size_t k = 0; k < padded_; ++k) s[k] *= band_[k] < gain.size() ? gain[band_[k]] * inverse_[k] : 0.0;
  std::vector<double> out = inverse_fft(s);
  out.resize(samples_);
  return out;
}

std::vector<double> DriveInverse::band_energy(const std::vector<double>& x) const {
  const std::vector<double> padded = padded_record(x);
  const Spectrum s = forward_fft(padded);
  std::vector<double> e(bands_.size(), 0.0);
  for (std::size_t k = 0; k < padded_; ++k) {
    if (band_[k] < e.size()) e[band_[k]] += std::norm(s[k]);
  }
  return e;
}

std::vector<std::complex<double>> DriveInverse::band_ratio(const std::vector<double>& measured,
                                                         const std::vector<double>& predicted) const {
  const Spectrum y = forward_fft(padded_record(measured)), p = forward_fft(padded_record(predicted));
  std::vector<std::complex<double>> cross(bands_.size(), 0.0);
  std::vector<double> power(bands_.size(), 0.0);
  for (std::size_t k = 1; k <= padded_ / 2; ++k) {
    if (band_[k] >= cross.size()) continue;
    cross[band_[k]] += y[k] * std::conj(p[k]);
    power[band_[k]] += std::norm(p[k]);
  }
  for (std::size_t b = 0; b < cross.size(); ++b) cross[b] = power[b] > 0.0 ? cross[b] / power[b] : 0.0;
  return cross;
}

}  // namespace rigctl
