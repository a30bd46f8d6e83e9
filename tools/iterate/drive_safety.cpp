#include "tools/iterate/drive_safety.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rigctl {

namespace {

// The predicted rod keeps 30 % clear of the rate detector's level: the
// detector also sees the sensor's noise, and the prediction's error on the
// first drive (before a measured ratio corrects it) was up to 15 % in the
// tests (docs/drive-iteration.md 3).
constexpr double kVelocityShare = 0.7;
// The predicted command (the hold included) may reach 80 % of the output
// limit: the rest is for the loop's correction of what the model missed
// (friction, the noise) and the prediction's own error.
constexpr double kEffortShare = 0.8;
// The predicted rod keeps 3 % of the trip range (`limits:` of the feedback,
// 5.5 mm of the quarter car's 184 mm) clear of it at either end: the
// prediction of a slow swing is good to a fraction of a millimetre, and the
// loop's tracking of the largest swing adds a few.
constexpr double kStrokeMargin = 0.03;
// The drive may pass the setpoint range by 10^-4 of its width (16 um on the
// quarter car, below its LVDT's 20 um noise): a target that holds at home,
// the range's bottom, and was resampled or quantised in a file comes back
// a fraction of a micrometre below it, and the drive follows the target there.
constexpr double kPositionTolerance = 1e-4;

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

}  // namespace

DriveLimits drive_limits(const RigConfig& c) {
  DriveLimits l;
  l.position_min = c.safety.setpoint_min;
  l.position_max = c.safety.setpoint_max;
  l.position_source = "safety.setpoint_range";
  l.stroke_min = l.position_min;
  l.stroke_max = l.position_max;
  l.stroke_source = l.position_source;
  for (const auto& lim : c.limits) {
    if (lim.channel != c.controller.feedback) continue;
    if (lim.min > l.position_min || lim.max < l.position_max) {
      l.position_min = std::max(l.position_min, lim.min);
      l.position_max = std::min(l.position_max, lim.max);
      l.position_source = "safety.setpoint_range and limits." + lim.channel;
    }
    const double margin = kStrokeMargin * (lim.max - lim.min);
    l.stroke_min = lim.min + margin;
    l.stroke_max = lim.max - margin;
    l.stroke_source = "limits." + lim.channel + " less " + fmt(100 * kStrokeMargin) + " %";
  }
  l.velocity_max = std::numeric_limits<double>::infinity();
  for (const auto& d : c.safety.detectors) {
    if (d.type != DetectorKind::kRate || d.channel != c.controller.feedback || !std::isfinite(d.max)) continue;
    if (kVelocityShare * d.max < l.velocity_max) {
      l.velocity_max = kVelocityShare * d.max;
      l.velocity_source = "safety.detectors." + d.name + " (" + fmt(kVelocityShare) + " x max " + fmt(d.max) + ")";
    }
  }
  const double output_limit = c.controller.type == ControllerKind::kPvp ? c.controller.pvp.output_limit
                                                                          : c.controller.pi.output_limit;
  l.effort_max = kEffortShare * output_limit;
  l.effort_source = "controller.output_limit (" + fmt(kEffortShare) + " x " + fmt(output_limit) + ")";
  return l;
}

DrivePeaks drive_peaks(const std::vector<double>& d, double op, double dt, const PredictedMotion& predicted) {
  DrivePeaks k;
  k.predicted = predicted;
  if (d.empty()) return k;
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  k.min = *lo;
  k.max = *hi;
  k.displacement = std::max(op - k.min, k.max - op);
  for (std::size_t i = 1; i < d.size(); ++i) k.velocity = std::max(k.velocity, std::abs(d[i] - d[i - 1]) / dt);
  return k;
}

DriveVerdict check_drive(const DrivePeaks& k, const DriveLimits& l, double op) {
  // Every limit's room as a factor on the drive's swing about the operating
  // point; the one with the least room is the limit that stops the drive.
  DriveVerdict v;
  v.fit_scale = std::numeric_limits<double>::infinity();
  auto take = [&](double scale, const std::string& why) {
    if (scale >= v.fit_scale) return;
    v.fit_scale = scale;
    if (scale < 1.0) {
      v.ok = false;
      v.reason = why;
    }
  };
  // slack: how far past the limit still counts as within it.
  auto range = [&](double low, double high, double limit_low, double limit_high, double slack, const std::string& what,
                   const std::string& source) {
    if (high > op) take((limit_high + slack - op) / (high - op), "stroke: " + what + fmt(high) + ", above " + source + " max " + fmt(limit_high));
    if (low < op) take((op - limit_low + slack) / (op - low), "stroke: " + what + fmt(low) + ", below " + source + " min " + fmt(limit_low));
  };
  range(k.min, k.max, l.position_min, l.position_max, kPositionTolerance * (l.position_max - l.position_min),
        "the drive reaches ", l.position_source);
  const PredictedMotion& p = k.predicted;
  range(p.rod_min, p.rod_max, l.stroke_min, l.stroke_max, 0.0, "the rod is predicted to reach ", l.stroke_source);
  if (p.rod_velocity > 0.0) {
    take(l.velocity_max / p.rod_velocity, "velocity: the rod is predicted to move at " + fmt(p.rod_velocity) +
                                               " beyond " + l.velocity_source + " " + fmt(l.velocity_max));
  }
  if (p.valve_effort > 0.0) {
    // The effort is nearly proportional to the swing (the hold aside): scale alike.
    take(l.effort_max / p.valve_effort, "flow: the drive needs a valve effort of " + fmt(p.valve_effort) +
                                            " beyond " + l.effort_source + " " + fmt(l.effort_max));
  }
  return v;
}

void scale_drive(std::vector<double>& d, double op, double scale) {
  for (double& x : d) x = op + (x - op) * scale;
}

}  // namespace rigctl
