// The FRFs of an identification record: the closed loop demand -> response
// (H1) and the plant command -> response with the demand as instrument
// (G = S_ry / S_ru, unbiased by the feedback: the noise the loop feeds back
// into the command is uncorrelated with the demand), the coherences and the
// noise floors, on the bins of the band.
#pragma once

#include <span>
#include <vector>

#include "tools/identify/frf_data.hpp"
#include "tools/identify/welch.hpp"

namespace rigctl {

struct IdentificationRecord {
  std::span<const double> demand;
  std::span<const double> command;
  std::vector<std::span<const double>> responses;  // in FrfData::responses order
};

// Fills frequency_hz, closed_loop, plant, command_coherence, noise_floor,
// response_psd and estimation.averages of `out` (channels already named),
// on the given bins of a segment, or with none given on every bin of the band.
void estimate_frf(const IdentificationRecord& record, const WelchSettings& settings, double band_min_hz,
                  double band_max_hz, const std::vector<std::size_t>& bins, FrfData& out);

}  // namespace rigctl
