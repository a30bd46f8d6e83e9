#include "tools/identify/mimo_frf.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/Dense>

namespace rigctl {

namespace {

using Eigen::Index;
using Eigen::MatrixXcd;

// The spectra of signals a and b conditioned on the set `rest` (Bendat and
// Piersol, conditioned spectral density): S_ab.r = S_ab - S_ar S_rr^-1 S_rb,
// in welch()'s convention S(i, j) = E[conj(X_i) X_j].
std::complex<double> conditioned(const MatrixXcd& s, Index a, Index b, const std::vector<Index>& rest) {
  if (rest.empty()) return s(a, b);
  const auto r = static_cast<Index>(rest.size());
  MatrixXcd s_rr(r, r), s_ar(1, r), s_rb(r, 1);
  for (Index i = 0; i < r; ++i) {
    s_ar(0, i) = s(a, rest[static_cast<std::size_t>(i)]);
    s_rb(i, 0) = s(rest[static_cast<std::size_t>(i)], b);
    for (Index j = 0; j < r; ++j) s_rr(i, j) = s(rest[static_cast<std::size_t>(i)], rest[static_cast<std::size_t>(j)]);
  }
  return s(a, b) - (s_ar * s_rr.completeOrthogonalDecomposition().solve(s_rb))(0, 0);
}

double partial_coherence(const MatrixXcd& s, Index drive, Index response, Index n_x) {
  std::vector<Index> rest;
  for (Index m = 0; m < n_x; ++m) {
    if (m != drive) rest.push_back(m);
  }
  const double s_xx = conditioned(s, drive, drive, rest).real();
  const double s_yy = conditioned(s, response, response, rest).real();
  const double denom = s_xx * s_yy;
  return denom > 0.0 ? std::min(1.0, std::norm(conditioned(s, drive, response, rest)) / denom) : 0.0;
}

void add_line(const MatrixXcd& s, Index n_x, Index n_y, double f, MimoFrf& out) {
  const MatrixXcd s_xx = s.topLeftCorner(n_x, n_x);
  const MatrixXcd s_xy = s.topRightCorner(n_x, n_y);
  // S_xy = S_xx H^T (Y = H X), so H^T = S_xx^-1 S_xy.
  const MatrixXcd h_t = s_xx.completeOrthogonalDecomposition().solve(s_xy);
  Eigen::VectorXd multiple(n_y);
  Eigen::MatrixXd partial(n_y, n_x);
  for (Index j = 0; j < n_y; ++j) {
    // Power the drives explain: S_xy(:, j)^H S_xx^-1 S_xy(:, j).
    const double explained = (s_xy.col(j).adjoint() * h_t.col(j))(0, 0).real();
    const double power = s(n_x + j, n_x + j).real();
    multiple(j) = power > 0.0 ? std::clamp(explained / power, 0.0, 1.0) : 0.0;
    for (Index m = 0; m < n_x; ++m) partial(j, m) = partial_coherence(s, m, n_x + j, n_x);
  }
  const Eigen::VectorXd sv = Eigen::JacobiSVD<MatrixXcd>(s_xx).singularValues();
  out.frequency_hz.push_back(f);
  out.value.push_back(h_t.transpose());
  out.multiple_coherence.push_back(multiple);
  out.partial_coherence.push_back(partial);
  out.input_condition.push_back(sv(sv.size() - 1) > 0.0 ? sv(0) / sv(sv.size() - 1) : INFINITY);
}

}  // namespace

MimoFrf estimate_mimo_frf(const std::vector<std::span<const double>>& drives,
                          const std::vector<std::span<const double>>& responses, const WelchSettings& settings,
                          double band_min_hz, double band_max_hz, const std::vector<std::size_t>& lines) {
  if (drives.empty() || responses.empty()) throw std::invalid_argument("mimo frf: needs at least one drive and one response");
  std::vector<std::span<const double>> signals = drives;
  signals.insert(signals.end(), responses.begin(), responses.end());
  const CrossSpectra s = welch(signals, settings);
  const auto n_x = static_cast<Index>(drives.size());
  const auto n_y = static_cast<Index>(responses.size());
  MimoFrf out;
  out.averages = s.averages;
  for (std::size_t k = 1; k < s.frequency_hz.size(); ++k) {
    const double f = s.frequency_hz[k];
    if (f < band_min_hz - 1e-9 || f > band_max_hz + 1e-9) continue;
    if (!lines.empty() && std::find(lines.begin(), lines.end(), k) == lines.end()) continue;
    add_line(s.pairs[k], n_x, n_y, f, out);
  }
  if (out.frequency_hz.empty()) throw std::invalid_argument("mimo frf: no line inside the band");
  return out;
}

}  // namespace rigctl
