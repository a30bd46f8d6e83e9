// Whole-record spectra for the drive iteration: the drive is made offline
// from whole records, so the inverse works on one FFT of the record (a
// non-causal filter) rather than on a running filter. Eigen's FFT.
#pragma once

#include <complex>
#include <functional>
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

// The record's content in [low_hz, high_hz] only (no mean), the record
// taken as periodic (for records that start and end alike, e.g. faded).
std::vector<double> band_limited(const std::vector<double>& x, double dt, double low_hz, double high_hz);

// x followed by `pad` samples that go from x.back() to x.front() along a
// half cosine: the record's periodic continuation has no step, so a filter
// made on its FFT puts no spike at the record's ends (a target that ramps
// from home to mid-stroke starts and ends at different levels).
std::vector<double> smoothly_padded(const std::vector<double>& x, std::size_t pad);
// The padding for the filters below: 2 s, longer than the ringing of any
// filter they apply (the inverse's pre- and post-ringing, the band's edges).
std::size_t smooth_pad_samples(double dt);

// The record's content in [low_hz, high_hz] (no mean), filtered on its
// smoothly padded continuation: what the iteration's error is judged on.
std::vector<double> band_passed(const std::vector<double>& x, double dt, double low_hz, double high_hz);

// x filtered by a frequency response (the same for the mirrored half, as
// its conjugate), on its smoothly padded continuation; `response` is asked
// for bins from 0 to the Nyquist frequency.
std::vector<double> filtered(const std::vector<double>& x, double dt,
                             const std::function<std::complex<double>(double f_hz)>& response);

}  // namespace rigctl
