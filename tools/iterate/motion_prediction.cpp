#include "tools/iterate/motion_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

// The ratio of measured to predicted is trusted within a factor of two
// either way: beyond it the model is too wrong for the check to lean on
// (the first drive's prediction would have been off by more than the
// margins), so the check keeps at least half its caution.
constexpr double kMinRatio = 0.5, kMaxRatio = 2.0;

// The largest |x'| by central differences.
double peak_rate(const std::vector<double>& x, double dt) {
  double peak = 0.0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) peak = std::max(peak, std::abs(x[i + 1] - x[i - 1]) / (2.0 * dt));
  return peak;
}

}  // namespace

ValveLaw valve_law(const RigConfig& c, double command_hold) {
  if (c.rig != RigKind::kQuarterCar) return {};
  const QuarterCarParams& p = c.quarter_car;
  // Flow continuity through the supply edge and the return edge at velocity v,
  // Q_in = Kv u sqrt(Ps - p_in), Q_out = Kv u sqrt(p_out), with the force
  // balance A1 p1 - A2 p2 = F (the static load of rod, wheel and body):
  // extending (v > 0) gives (v / Kv u)^2 = (A1 Ps - F) / (A1^3 + A2^3),
  // retracting (F + A2 Ps) / (A1^3 + A2^3). The inertia forces are left out
  // (small beside the supply's 40 kN); the measured ratio takes up the rest.
  const double weight = (p.mass_rod + p.mass_wheel + p.mass_body) * p.gravity;
  const double cubes = std::pow(p.area_cap, 3) + std::pow(p.area_rod, 3);
  const double out_force = p.area_cap * p.supply_pressure - weight, in_force = p.area_rod * p.supply_pressure + weight;
  const double out_speed = out_force > 0.0 ? p.valve_flow_gain * std::sqrt(out_force / cubes) : 0.0;
  const double in_speed = p.valve_flow_gain * std::sqrt(in_force / cubes);
  return [=](double v) {
    const double speed = v >= 0.0 ? out_speed : in_speed;  // [m/s] per unit command
    return speed > 0.0 ? command_hold + v / speed : std::numeric_limits<double>::infinity();
  };
}

PredictedMotion predict_motion(const LoopPaths& paths, const std::vector<double>& drive, double dt,
                               double command_hold, const ValveLaw& law, const PredictionCorrection& k) {
  PredictedMotion m;
  if (drive.empty()) return m;
  // The rod: the closed loop's T from the drive, 1 at rest (the loop's integral).
  const auto rod = filtered(drive, dt, [&](double f) { return f > 0.0 ? paths.feedback.at(f) : 1.0; });
  const auto [lo, hi] = std::minmax_element(rod.begin(), rod.end());
  m.rod_min = *lo;
  m.rod_max = *hi;
  m.rod_velocity = k.velocity * peak_rate(rod, dt);
  if (law) {
    for (std::size_t i = 1; i + 1 < rod.size(); ++i) {
      m.valve_effort = std::max(m.valve_effort, std::abs(law((rod[i + 1] - rod[i - 1]) / (2.0 * dt))));
    }
    m.valve_effort *= k.effort;
    return m;
  }
  // The command's deviation from its hold: T / G, which falls to 0 at rest
  // (a held position needs only the hold); below the first line it falls
  // with the frequency as a velocity's command does.
  const double f0 = paths.command.frequency_hz.front();
  const auto u = filtered(drive, dt, [&](double f) {
    return f >= f0 ? paths.command.at(f) : paths.command.at(f0) * (f / f0);
  });
  for (double v : u) m.valve_effort = std::max(m.valve_effort, std::abs(command_hold + v));
  m.valve_effort *= k.effort;
  return m;
}

MeasuredMotion measured_motion(const std::vector<double>& feedback, const std::vector<double>& command, double dt,
                               double band_max_hz) {
  MeasuredMotion m;
  // The rod's velocity over the band the drive is made in: the sensor's
  // noise above it is not the rod's motion (20 um of LVDT noise is 8 mm/s
  // from one tick to the next).
  m.rod_velocity = peak_rate(band_passed(feedback, dt, 0.0, band_max_hz), dt);
  for (double u : command) m.valve_effort = std::max(m.valve_effort, std::abs(u));
  return m;
}

PredictionCorrection correction_from(const PredictedMotion& p, const MeasuredMotion& m) {
  PredictionCorrection k;
  if (p.rod_velocity > 0.0 && m.rod_velocity > 0.0) k.velocity = std::clamp(m.rod_velocity / p.rod_velocity, kMinRatio, kMaxRatio);
  if (p.valve_effort > 0.0 && m.valve_effort > 0.0) k.effort = std::clamp(m.valve_effort / p.valve_effort, kMinRatio, kMaxRatio);
  return k;
}

}  // namespace rigctl
