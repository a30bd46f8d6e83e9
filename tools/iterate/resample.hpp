// A record resampled to another period, band-limited on the way: each new
// sample is the old ones weighted by a Hann-windowed sinc whose cut-off is
// 90 % of the lower Nyquist frequency of the two rates (so a target
// sampled at 1 kHz loses what 400 Hz cannot hold instead of folding it
// down, and one sampled at 100 Hz gains nothing above its own 50 Hz). The
// weights are normalised to sum to one, so a held value stays exactly that
// value; beyond the record's ends its first and last values are held.
#pragma once

#include <vector>

namespace rigctl {

// x sampled every from_s, resampled to every to_s over the same span (the
// first sample at the same time); x itself when the periods agree.
std::vector<double> resample(const std::vector<double>& x, double from_s, double to_s);

}  // namespace rigctl
