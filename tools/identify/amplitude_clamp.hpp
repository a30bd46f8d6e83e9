// The largest excitation peak a rig allows about an operating point, from
// its own limits: the stroke (safety.setpoint_range and the feedback's
// `limits:` range), the tracking-error detectors and the valve's range seen
// through the controller's gain on the demand. Each bound keeps a margin for
// the loop's own amplification (a response can exceed its demand near the
// loop's resonance), said beside each factor.
#pragma once

#include <string>

#include "config/rig_config.hpp"

namespace rigctl {

struct AmplitudeClamp {
  double limit = 0.0;  // [the feedback's unit]
  std::string reason;  // which limit binds, e.g. "safety.detectors.tracking (0.4 x max 0.02)"
};

// Throws ConfigError when the operating point is outside the setpoint range.
AmplitudeClamp amplitude_clamp(const RigConfig& config, double operating_point, double band_min_hz);

// The controller's gain from demand to valve command at frequency f [Hz]:
// PI |kp + ki Ts / (1 - z^-1)|, P+V+dP ke (only Ke sees the demand).
double demand_to_command_gain(const ControllerConfig& controller, double f_hz, double period_s);

}  // namespace rigctl
