// Excitation of several drives at once for the matrix of frequency
// responses (tools/identify/mimo_frf.hpp): per drive a random-phase
// multisine on the same lines, in R >= n_drives realisations whose phases
// are rotated by 2 pi r m / R (drive m, realisation r) so that summed over
// the realisations the drives are exactly uncorrelated on every line
// (orthogonal multisines, Dobrowiecki, Pintelon and Schoukens 2006): the
// input spectral matrix S_xx is diagonal and H = S_yx S_xx^-1 is as well
// conditioned as the lines are excited. One period per realisation and
// drive; a rig plays each realisation for settle + 1 periods and the
// analysis takes the last one (a periodic, leakage-free steady state).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rigctl {

struct MimoExcitation {
  std::size_t period_ticks = 0;
  std::size_t realisations = 0;
  // periods[r][m]: realisation r, drive m, one period of period_ticks values, peak `amplitude`.
  std::vector<std::vector<std::vector<double>>> periods;
};

// lines: bins of a period_ticks-long period (as Excitation::lines). Throws
// std::invalid_argument when realisations < drives or lines are empty or
// outside the period's Nyquist.
MimoExcitation orthogonal_multisines(const std::vector<std::size_t>& lines, std::size_t period_ticks, std::size_t drives,
                                     std::size_t realisations, double amplitude, uint64_t seed);

// The records a rig plays: per drive, each realisation repeated
// (settle_periods + 1) times, realisations one after another.
std::vector<std::vector<double>> played_records(const MimoExcitation& e, std::size_t settle_periods);
// From the rig's records of played_records' length (per channel), the
// analysed part: the last period of each realisation, concatenated.
std::vector<std::vector<double>> steady_periods(const std::vector<std::vector<double>>& recorded,
                                                const MimoExcitation& e, std::size_t settle_periods);

}  // namespace rigctl
