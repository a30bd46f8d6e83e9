// The regularised inverse of a rig's matrix of frequency responses (drives
// -> responses, tools/identify/mimo_frf.hpp) on one record's FFT bins, for
// drive iteration with several drives: every drive moves every response
// (each post of a two-poster rig lifts both ends of the car), so the update
// is one vector of drives per line, d(k+1) = d(k) + H^+ G e(k), not one
// channel at a time.
//
// Per line, H^+ is a weighted, regularised pseudo-inverse by the SVD of
// W^1/2 H = U S V^H: H^+ = V diag(s / (s^2 + eps^2)) U^H W^1/2, which
// minimises |W^1/2 (e - H d)|^2 + eps^2 |d|^2 (more responses than drives:
// least squares with the weights W). eps per line is the largest of
//  * a fraction of the line's own largest singular value: the inverse's
//    condition per line is capped (a direction the rig passes 20 times
//    less than its best at that frequency gets a bounded gain). Relative to
//    the line, not the band as the SISO inverse is: a two-poster rig's body
//    responses fall 40 dB per decade above the body modes, and a cap from
//    the band's largest value would leave every line above them barely
//    inverted (tried: the first drive's error stayed at 20-50 %);
//  * a small fraction of the band's largest singular value: a line the rig
//    hardly passes at all gets no large drive;
//  * the line's own uncertainty: the largest singular value times the
//    random error of an H1 estimate at the line's least multiple
//    coherence, sqrt((1 - g^2) / (2 n g^2)) over n averages (Bendat and
//    Piersol 9.3): a direction smaller than what the measurement can
//    resolve is not inverted.
// Lines whose least multiple coherence is under the gate are not inverted.
// The record is zero-padded (the inverse is non-causal: pre- and
// post-ringing fall into the padding).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "tools/identify/mimo_frf.hpp"
#include "tools/iterate/drive_inverse.hpp"

namespace rigctl {

using Records = std::vector<std::vector<double>>;  // one record per channel, same length

struct MimoInverseSettings {
  double band_min_hz = 0.5;      // [Hz] the band the error is judged on
  double band_max_hz = 30.0;     // [Hz] no drive content above it
  double coherence_gate = 0.8;   // least multiple coherence of a line that is inverted
  double regularisation = 0.05;  // eps / the line's largest singular value: |H^+| at most 10 / sigma_1 per line
  double floor = 1e-3;           // eps / the band's largest singular value: 60 dB below the best line
  double pad_s = 2.0;            // [s] zeros after the record
  std::vector<double> weights;   // per response (empty: all 1)
};

// What the regularisation did, for the report.
struct MimoInverseReport {
  std::size_t lines_inverted = 0, lines_gated = 0;
  std::size_t lines_rank_reduced = 0;  // lines where a singular value fell below eps
  double largest_singular_value = 0.0;
  double eps_floor = 0.0;              // the band floor's eps
};

class MimoDriveInverse {
 public:
  MimoDriveInverse(const MimoFrf& frf, std::size_t samples, double period_s, const MimoInverseSettings& settings);

  // H^+ (G e): errors, one record per response; gain(b, j): band b's gain on
  // response j's error (GainBands of drive_inverse.hpp). One record per drive.
  Records apply(const Records& errors, const Eigen::MatrixXd& gain) const;
  // Per gain band (rows) and channel (columns), the records' energy.
  Eigen::MatrixXd band_energy(const Records& x) const;

  const GainBands& bands() const { return bands_; }
  const MimoInverseReport& report() const { return report_; }
  std::size_t drives() const { return n_x_; }
  std::size_t responses() const { return n_y_; }

 private:
  std::size_t samples_, padded_;
  std::size_t n_x_ = 0, n_y_ = 0;
  GainBands bands_;
  std::vector<Eigen::MatrixXcd> inverse_;  // per padded bin up to the Nyquist, n_x x n_y
  std::vector<std::size_t> band_;          // per padded bin: its gain band, or bands_.size() outside
  MimoInverseReport report_;
};

// H at f by linear interpolation between lines (the first or last line outside).
Eigen::MatrixXcd mimo_frf_at(const MimoFrf& frf, double f_hz);
double least_coherence_at(const MimoFrf& frf, double f_hz);

// The FRF of transformed responses y' = T y (e.g. body heave and pitch from
// the displacements over the two axles): H' = T H. The coherences are those
// of the measured responses (each transformed response is judged by the
// least coherent of the responses it is made of).
MimoFrf transformed(const MimoFrf& frf, const Eigen::MatrixXd& t);

}  // namespace rigctl
