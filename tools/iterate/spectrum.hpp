// Whole-record spectra for the drive iteration: the drive is made offline
// from whole records, so the inverse works on one FFT of the record (a
// non-causal filter) rather than on a running filter. Eigen's FFT.
#pragma once

#include <complex>
#include <vector>

namespace rigctl {

using Spectrum = std::vector<std::complex<double>>;

// Full-length spectrum of a real record (n bins, bin k at k / (n dt) Hz,
// the upper half the mirror image).
Spectrum forward_fft(const std::vector<double>& x);
// The real record of a spectrum whose upper half mirrors the lower.
std::vector<double> inverse_fft(const Spectrum& x);

// Frequency of bin k of an n-point record at period dt, folded: 0..1/(2 dt).
double bin_frequency_hz(std::size_t k, std::size_t n, double dt);

// The record's content in [low_hz, high_hz] only (no mean): what the
// iteration's error is judged on.
std::vector<double> band_limited(const std::vector<double>& x, double dt, double low_hz, double high_hz);

}  // namespace rigctl
