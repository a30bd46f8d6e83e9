#include "tools/iterate/drive_safety.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rigctl {

namespace {

// The response may overshoot the drive's velocity (the loop's resonance,
// the sensor noise the rate detector also sees): the drive keeps 30 % clear
// of the rate detector's level.
constexpr double kVelocityShare = 0.7;
// The valve's command also carries the error correction and the leakage's
// hold (-0.043 on the quarter car): the drive may need at most 80 % of it.
constexpr double kEffortShare = 0.8;

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
  for (const auto& lim : c.limits) {
    if (lim.channel != c.controller.feedback) continue;
    if (lim.min > l.position_min || lim.max < l.position_max) {
      l.position_min = std::max(l.position_min, lim.min);
      l.position_max = std::min(l.position_max, lim.max);
      l.position_source = "safety.setpoint_range and limits." + lim.channel;
    }
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

double predicted_valve_effort(const RigConfig& c, double v, double command_hold) {
  if (c.rig != RigKind::kQuarterCar) return 0.0;
  const QuarterCarParams& p = c.quarter_car;
  // Flow continuity through the supply edge and the return edge at velocity v,
  // Q_in = Kv u sqrt(Ps - p_in), Q_out = Kv u sqrt(p_out), with the force
  // balance A1 p1 - A2 p2 = F (the static load of rod, wheel and body):
  // extending (v > 0) gives (v / Kv u)^2 = (A1 Ps - F) / (A1^3 + A2^3),
  // retracting (F + A2 Ps) / (A1^3 + A2^3). The inertia forces are left out:
  // they are small beside the supply's force on the quarter car (40 kN).
  const double weight = (p.mass_rod + p.mass_wheel + p.mass_body) * p.gravity;
  const double cubes = std::pow(p.area_cap, 3) + std::pow(p.area_rod, 3);
  const double drive_force = v >= 0.0 ? p.area_cap * p.supply_pressure - weight : p.area_rod * p.supply_pressure + weight;
  if (drive_force <= 0.0) return std::numeric_limits<double>::infinity();
  const double speed_per_command = p.valve_flow_gain * std::sqrt(drive_force / cubes);
  return std::abs(command_hold + v / speed_per_command);
}

DrivePeaks drive_peaks(const RigConfig& c, const std::vector<double>& d, double op, double command_hold) {
  DrivePeaks k;
  if (d.empty()) return k;
  const auto [lo, hi] = std::minmax_element(d.begin(), d.end());
  k.min = *lo;
  k.max = *hi;
  k.displacement = std::max(op - k.min, k.max - op);
  const double dt = c.loop.period_s;
  for (std::size_t i = 1; i < d.size(); ++i) {
    const double v = (d[i] - d[i - 1]) / dt;
    k.velocity = std::max(k.velocity, std::abs(v));
    k.valve_effort = std::max(k.valve_effort, predicted_valve_effort(c, v, command_hold));
  }
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
  if (k.max > op) {
    take((l.position_max - op) / (k.max - op),
         "stroke: the drive reaches " + fmt(k.max) + ", above " + l.position_source + " max " + fmt(l.position_max));
  }
  if (k.min < op) {
    take((op - l.position_min) / (op - k.min),
         "stroke: the drive reaches " + fmt(k.min) + ", below " + l.position_source + " min " + fmt(l.position_min));
  }
  if (k.velocity > 0.0) {
    take(l.velocity_max / k.velocity,
         "velocity: the drive moves at " + fmt(k.velocity) + " beyond " + l.velocity_source + " " + fmt(l.velocity_max));
  }
  if (k.valve_effort > 0.0) {
    // The effort is proportional to the velocity (the hold aside): scale alike.
    take(l.effort_max / k.valve_effort, "flow: the drive needs a valve effort of " + fmt(k.valve_effort) +
                                            " beyond " + l.effort_source + " " + fmt(l.effort_max));
  }
  return v;
}

void scale_drive(std::vector<double>& d, double op, double scale) {
  for (double& x : d) x = op + (x - op) * scale;
}

}  // namespace rigctl
