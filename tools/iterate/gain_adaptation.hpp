// The iteration's gain per band, adapted from what the rig did. After a
// drive is played, the response is compared with what the model predicted
// for that very drive, band by band: r = measured / predicted (the rig's
// gain over the model's, with its phase). An update alpha H^-1 e then
// leaves (1 - alpha r) e of the error, smallest for alpha = Re(r) / |r|^2.
// A band where the rig's phase is too far from the model's for an update to
// take out a fair share of its error is gated: it gets no correction.
#pragma once

#include <complex>
#include <cstddef>
#include <vector>

namespace rigctl {

struct GainUpdate {
  std::vector<double> gain;         // alpha per band
  std::vector<std::size_t> gated;   // bands closed by this update (their gain 0)
};

// ratio: measured over predicted per band (DriveInverse::band_ratio);
// energy: the predicted record's energy per band (bands without a fair
// share of it were not measured and keep their gain). Band 0, below the
// band, keeps its gain.
GainUpdate adapt_gain(const std::vector<std::complex<double>>& ratio, const std::vector<double>& energy,
                      const std::vector<double>& current);

}  // namespace rigctl
