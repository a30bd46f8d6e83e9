#include "tools/identify/amplitude_clamp.hpp"

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "config/config_reader.hpp"

namespace rigctl {

namespace {

// Half the distance to a position bound: the response may swing up to twice
// the demand's peak near a lightly damped loop's resonance (|T| <= 2).
constexpr double kStrokeShare = 0.5;
// The tracking error e = S r: |S| <= 2 for any loop with a 30 degree phase
// margin, so 0.4 x max keeps the error below 0.8 x the detector's level.
constexpr double kTrackingShare = 0.4;
// Half the valve's range for the excitation: the rest holds the operating
// point (the quarter car's leakage needs -0.043) and carries the noise.
constexpr double kValveShare = 0.5;

struct Bound {
  double limit = std::numeric_limits<double>::infinity();
  std::string reason;
  void take(double value, const std::string& why) {
    if (value < limit) {
      limit = value;
      reason = why;
    }
  }
};

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

}  // namespace

double demand_to_command_gain(const ControllerConfig& c, double f_hz, double period_s) {
  switch (c.type) {
    case ControllerKind::kPi: {
      const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f_hz * period_s);
      return std::abs(c.pi.kp + c.pi.ki * period_s / (1.0 - 1.0 / z));
    }
    case ControllerKind::kPvp: return c.pvp.ke;
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: break;
  }
  throw std::invalid_argument(std::string("identification needs a position controller (pi, pvp), not ") +
                              std::string(to_string(c.type)));
}

AmplitudeClamp amplitude_clamp(const RigConfig& c, double op, double band_min_hz) {
  const auto& s = c.safety;
  if (!(op >= s.setpoint_min && op <= s.setpoint_max)) {
    throw ConfigError(c.file + ": identify.operating_point: " + fmt(op) + " is outside safety.setpoint_range [" +
                      fmt(s.setpoint_min) + ", " + fmt(s.setpoint_max) + "]");
  }
  Bound b;
  b.take(kStrokeShare * std::min(op - s.setpoint_min, s.setpoint_max - op),
         "safety.setpoint_range (" + fmt(kStrokeShare) + " x the distance from the operating point)");
  for (const auto& l : c.limits) {
    if (l.channel != c.controller.feedback) continue;
    b.take(kStrokeShare * std::min(op - l.min, l.max - op),
           "limits." + l.channel + " (" + fmt(kStrokeShare) + " x the distance from the operating point)");
  }
  for (const auto& d : s.detectors) {
    const bool on_feedback = d.channel.empty() || d.channel == c.controller.feedback;
    if (d.type == DetectorKind::kTrackingError && on_feedback && std::isfinite(d.max)) {
      b.take(kTrackingShare * d.max, "safety.detectors." + d.name + " (" + fmt(kTrackingShare) + " x max " + fmt(d.max) + ")");
    }
  }
  const double gain = demand_to_command_gain(c.controller, band_min_hz, c.loop.period_s);
  const double output_limit = c.controller.type == ControllerKind::kPi ? c.controller.pi.output_limit
                                                                       : c.controller.pvp.output_limit;
  if (gain > 0.0) {
    b.take(kValveShare * output_limit / gain, "controller.output_limit (" + fmt(kValveShare) + " x " +
                                                  fmt(output_limit) + " over the controller's demand gain " + fmt(gain) + ")");
  }
  return AmplitudeClamp{b.limit, b.reason};
}

}  // namespace rigctl
