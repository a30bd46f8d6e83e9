#include "tools/iterate/mimo_inverse.hpp"

#include <algorithm>
#include <initializer_list>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

using Eigen::Index;

std::size_t line_below(const MimoFrf& frf, double f) {
  const auto it = std::upper_bound(frf.frequency_hz.begin(), frf.frequency_hz.end(), f);
  return it == frf.frequency_hz.begin() ? 0 : static_cast<std::size_t>(it - frf.frequency_hz.begin()) - 1;
}

double interpolation_weight(const MimoFrf& frf, std::size_t k, double f) {
  if (k + 1 >= frf.frequency_hz.size() || f <= frf.frequency_hz[k]) return 0.0;
  const double w = (f - frf.frequency_hz[k]) / (frf.frequency_hz[k + 1] - frf.frequency_hz[k]);
  return std::clamp(w, 0.0, 1.0);
}

// Random error of an H1 estimate relative to |H| (Bendat and Piersol 9.3).
double h1_relative_error(double coherence, int averages) {
  if (coherence <= 0.0 || averages <= 0) return 1.0;
  return std::sqrt((1.0 - coherence) / (2.0 * averages * coherence));
}

Eigen::VectorXd response_weights(const MimoInverseSettings& s, std::size_t n_y) {
  if (s.weights.empty()) return Eigen::VectorXd::Ones(static_cast<Index>(n_y));
  if (s.weights.size() != n_y) throw std::invalid_argument("mimo inverse: one weight per response is needed");
  Eigen::VectorXd w(static_cast<Index>(n_y));
  for (std::size_t j = 0; j < n_y; ++j) {
    if (!(s.weights[j] > 0.0)) throw std::invalid_argument("mimo inverse: weights must be positive");
    w(static_cast<Index>(j)) = std::sqrt(s.weights[j]);
  }
  return w;
}

}  // namespace

Eigen::MatrixXcd mimo_frf_at(const MimoFrf& frf, double f) {
  const std::size_t k = line_below(frf, f);
  const double w = interpolation_weight(frf, k, f);
  if (w == 0.0) return frf.value[k];
  return (1.0 - w) * frf.value[k] + w * frf.value[k + 1];
}

double least_coherence_at(const MimoFrf& frf, double f) {
  const std::size_t k = line_below(frf, f);
  const double w = interpolation_weight(frf, k, f);
  const double here = frf.multiple_coherence[k].minCoeff();
  return w == 0.0 ? here : (1.0 - w) * here + w * frf.multiple_coherence[k + 1].minCoeff();
}

MimoFrf transformed(const MimoFrf& frf, const Eigen::MatrixXd& t) {
  if (frf.value.empty() || t.cols() != frf.value.front().rows()) {
    throw std::invalid_argument("transform: needs one column per measured response");
  }
  MimoFrf out = frf;
  for (std::size_t k = 0; k < frf.value.size(); ++k) {
    out.value[k] = t.cast<std::complex<double>>() * frf.value[k];
    Eigen::VectorXd least(t.rows());
    for (Index r = 0; r < t.rows(); ++r) {
      double c = 1.0;
      for (Index j = 0; j < t.cols(); ++j) {
        if (t(r, j) != 0.0) c = std::min(c, frf.multiple_coherence[k](j));
      }
      least(r) = c;
    }
    out.multiple_coherence[k] = least;
    out.partial_coherence[k] = Eigen::MatrixXd::Constant(t.rows(), frf.value[k].cols(), NAN);  // not defined for T y
  }
  return out;
}

MimoDriveInverse::MimoDriveInverse(const MimoFrf& frf, std::size_t samples, double period_s, const MimoInverseSettings& s)
    : samples_(samples),
      padded_(samples + static_cast<std::size_t>(std::llround(s.pad_s / period_s))),
      bands_(gain_bands(s.band_min_hz, s.band_max_hz)) {
  if (frf.value.empty()) throw std::invalid_argument("mimo inverse: the FRF has no line");
  n_y_ = static_cast<std::size_t>(frf.value.front().rows());
  n_x_ = static_cast<std::size_t>(frf.value.front().cols());
  const Eigen::VectorXd w_half = response_weights(s, n_y_);
  for (std::size_t k = 0; k < frf.value.size(); ++k) {
    if (frf.frequency_hz[k] <= s.band_max_hz) {
      report_.largest_singular_value = std::max(report_.largest_singular_value,
          Eigen::JacobiSVD<Eigen::MatrixXcd>(w_half.asDiagonal() * frf.value[k]).singularValues()(0));
    }
  }
  report_.eps_floor = s.floor * report_.largest_singular_value;
  const std::size_t half = padded_ / 2;
  inverse_.assign(half + 1, Eigen::MatrixXcd::Zero(static_cast<Index>(n_x_), static_cast<Index>(n_y_)));
  band_.assign(half + 1, bands_.size());
  for (std::size_t k = 0; k <= half; ++k) {
    const double f = bin_frequency_hz(k, padded_, period_s);
    if (f > s.band_max_hz) continue;
    band_[k] = bands_.band_of(f);
    const double coherence = least_coherence_at(frf, f);
    if (coherence < s.coherence_gate) {
      ++report_.lines_gated;
      continue;
    }
    const Eigen::MatrixXcd hw = w_half.asDiagonal() * mimo_frf_at(frf, f);
    const Eigen::JacobiSVD<Eigen::MatrixXcd> svd(hw, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    const double eps = std::max({report_.eps_floor, s.regularisation * sv(0), sv(0) * h1_relative_error(coherence, frf.averages)});
    Eigen::VectorXcd gain(sv.size());
    for (Index i = 0; i < sv.size(); ++i) gain(i) = sv(i) / (sv(i) * sv(i) + eps * eps);
    if (sv.minCoeff() < eps) ++report_.lines_rank_reduced;
    inverse_[k] = svd.matrixV() * gain.asDiagonal() * svd.matrixU().adjoint() * w_half.asDiagonal();
    ++report_.lines_inverted;
  }
}

Records MimoDriveInverse::apply(const Records& errors, const Eigen::MatrixXd& gain) const {
  if (errors.size() != n_y_) throw std::invalid_argument("mimo inverse: one error record per response is needed");
  std::vector<Spectrum> e;
  for (const auto& x : errors) {
    std::vector<double> padded(padded_, 0.0);
    std::copy_n(x.begin(), std::min(x.size(), samples_), padded.begin());
    e.push_back(forward_fft(padded));
  }
  std::vector<Spectrum> d(n_x_, Spectrum(padded_, 0.0));
  Eigen::VectorXcd line(static_cast<Index>(n_y_));
  for (std::size_t k = 0; k <= padded_ / 2; ++k) {
    if (band_[k] >= bands_.size()) continue;
    for (std::size_t j = 0; j < n_y_; ++j) line(static_cast<Index>(j)) = gain(static_cast<Index>(band_[k]), static_cast<Index>(j)) * e[j][k];
    const Eigen::VectorXcd dk = inverse_[k] * line;
    for (std::size_t m = 0; m < n_x_; ++m) {
      d[m][k] = dk(static_cast<Index>(m));
      if (k != 0 && 2 * k != padded_) d[m][padded_ - k] = std::conj(dk(static_cast<Index>(m)));  // a real record
    }
  }
  Records out;
  for (const auto& dm : d) {
    std::vector<double> x = inverse_fft(dm);
    x.resize(samples_);
    out.push_back(std::move(x));
  }
  return out;
}

Eigen::MatrixXd MimoDriveInverse::band_energy(const Records& x) const {
  Eigen::MatrixXd energy = Eigen::MatrixXd::Zero(static_cast<Index>(bands_.size()), static_cast<Index>(x.size()));
  for (std::size_t c = 0; c < x.size(); ++c) {
    std::vector<double> padded(padded_, 0.0);
    std::copy_n(x[c].begin(), std::min(x[c].size(), samples_), padded.begin());
    const Spectrum s = forward_fft(padded);
    for (std::size_t k = 0; k <= padded_ / 2; ++k) {
      if (band_[k] < bands_.size()) energy(static_cast<Index>(band_[k]), static_cast<Index>(c)) += std::norm(s[k]);
    }
  }
  return energy;
}

}  // namespace rigctl
