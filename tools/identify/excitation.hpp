// The band-limited signals `rigctl identify` adds to the demand. Each is a
// table of one value per control tick, its peak exactly the requested
// amplitude, its power inside the band: lines (multisine), a sweep (chirp)
// or noise with 1/f power (pink). The multisine is a random-odd one: only
// odd bins of a segment, one in three of them left out. The second-order
// distortion of the rig (the valve's square-root orifice law, the asymmetric
// cylinder) falls on the even bins, where it cannot bias the response (with
// every bin excited it biased the quarter car's plant FRF by about 1 dB per
// millimetre of excitation at 0.5 Hz), and the bins left out show the
// odd-order distortion (friction, hysteresis) that no coherence reveals: a
// periodic excitation of a nonlinear rig gives a periodic, fully coherent,
// response. The periodic kinds repeat every Welch segment, so the estimate
// averages whole periods with a rectangular window and has no leakage; pink
// noise is averaged with Hann windows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "config/excitation_kind.hpp"

namespace rigctl {

struct ExcitationSpec {
  ExcitationKind kind = ExcitationKind::kMultisine;
  double band_min_hz = 0.5;
  double band_max_hz = 30.0;
  double amplitude = 0.0;       // peak |value| [the feedback's unit]
  double duration_s = 30.0;     // the table's length (rounded down to whole segments when periodic)
  double resolution_hz = 0.25;  // one segment lasts 1 / resolution_hz
  double period_s = 0.0025;     // the control period: one value per tick
  uint64_t seed = 1;            // pink noise's phases
};

struct Excitation {
  std::vector<double> values;      // one per tick from the excitation's start
  std::size_t segment_ticks = 0;   // Welch segment (and, when periodic, the period)
  bool periodic = false;
  std::vector<std::size_t> lines;  // multisine: the excited bins of a segment (the FRF's frequencies); else empty: every bin of the band
};

// Throws std::invalid_argument naming the bad field (band outside (0,
// Nyquist), duration shorter than two segments, amplitude not finite).
Excitation make_excitation(const ExcitationSpec& spec);

// Segment length in ticks for a resolution.
std::size_t segment_ticks(double resolution_hz, double period_s);

}  // namespace rigctl
