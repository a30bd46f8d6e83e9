// The regularised inverse of the drive FRF on one record's FFT bins, and the
// frequency-dependent gain of the iteration (d(k+1) = d(k) + alpha(f) H^-1 e(k)).
//
// Inverse: Tikhonov, H^-1 ~ conj(H) / (|H|^2 + eps^2) with eps a fraction of
// the largest |H| in the band, so a line the rig hardly passes gets a bounded
// gain instead of an unbounded one; lines whose coherence is below the gate
// are not inverted at all (0: the measurement says nothing there). The
// record is padded before the FFT with a smooth return from its end to its
// start: the inverse is non-causal (the drive is made offline) and its pre-
// and post-ringing fall into the padding instead of wrapping round the
// record, and a record that ends elsewhere than it starts has no step.
#pragma once

#include <vector>

#include "tools/iterate/drive_frf.hpp"
#include "tools/iterate/spectrum.hpp"

namespace rigctl {

struct InverseSettings {
  double band_min_hz = 0.5;     // [Hz] the band the error is judged on
  double band_max_hz = 30.0;    // [Hz] no drive content above it
  double coherence_gate = 0.8;  // lines below it are not inverted
  // eps / max|H|: caps |H^-1| at 1 / (2 eps) = 10 / max|H| (20 dB above the
  // band's best line), well above what the quarter car's wheel needs at
  // 30 Hz (|H| about 0.3) and far below what noise on a weak line would ask.
  double regularisation = 0.05;
  double pad_s = 2.0;           // [s] after the record: its smooth return to the start (spectrum.hpp)
};

// Bands in which the iteration's gain is adjusted: below the band, then
// one-third octaves across it.
struct GainBands {
  std::vector<double> edges_hz;  // band b is [edges[b], edges[b + 1])
  std::size_t band_of(double f_hz) const;
  std::size_t size() const { return edges_hz.size() - 1; }
};
GainBands gain_bands(double band_min_hz, double band_max_hz);

class DriveInverse {
 public:
  DriveInverse(const DriveFrf& frf, std::size_t samples, double period_s, const InverseSettings& settings);

  // alpha(f) H^-1 x for a record of `samples` samples; gain: one per gain band.
  std::vector<double> apply(const std::vector<double>& x, const std::vector<double>& gain) const;
  // Per gain band, the record's energy (for telling where the error grew).
  std::vector<double> band_energy(const std::vector<double>& x) const;
  // Per gain band, how the rig answered against the model: sum Y conj(P) /
  // sum |P|^2 over the band's bins, Y the measured and P the predicted
  // record (deviations from rest); 0 where P has no energy.
  std::vector<std::complex<double>> band_ratio(const std::vector<double>& measured,
                                               const std::vector<double>& predicted) const;

  const GainBands& bands() const { return bands_; }
  std::size_t lines_gated() const { return gated_; }

 private:
  std::vector<double> padded_record(const std::vector<double>& x) const;

  std::size_t samples_, padded_;
  double period_s_;
  GainBands bands_;
  Spectrum inverse_;             // per padded bin
  std::vector<std::size_t> band_;  // per padded bin: its gain band, or size() outside
  std::size_t gated_ = 0;
};

}  // namespace rigctl
