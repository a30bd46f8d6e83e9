// The optional `identify:` section: how `rigctl identify` measures the rig's
// frequency response (docs/frf-files.md). Every key is optional; the command
// line overrides each one.
#pragma once

#include <optional>

#include "config/excitation_kind.hpp"

namespace rigctl {

class ConfigReader;

struct IdentifyConfig {
  ExcitationKind excitation = ExcitationKind::kMultisine;
  // [Hz] the band the excitation covers and the FRF is reported over.
  double band_min_hz = 0.5;
  double band_max_hz = 30.0;
  // Peak of the excitation about the operating point, in the feedback's unit;
  // unset: the clamp from the rig's limits (tools/identify/amplitude_clamp.hpp).
  std::optional<double> amplitude;
  // [s] of excitation, the first segment (the loop settling into it) included.
  double duration_s = 30.0;
  // [Hz] frequency resolution: one Welch segment lasts 1 / resolution.
  double resolution_hz = 0.25;
  // The demand held while the excitation is added; unset: the middle of
  // safety.setpoint_range (mid-stroke).
  std::optional<double> operating_point;
  // [s] held at the operating point before the excitation starts.
  double settle_s = 2.0;
};

// Strict: unknown keys and bad values are ConfigErrors naming identify.KEY.
IdentifyConfig read_identify(ConfigReader r);

}  // namespace rigctl
