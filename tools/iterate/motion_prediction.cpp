#include "tools/iterate/motion_prediction.hpp"

#include <algorithm>
#include <cmath>

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

PredictedMotion predict_motion(const LoopPaths& paths, const std::vector<double>& drive, double dt,
                               double command_hold, const PredictionCorrection& k) {
  PredictedMotion m;
  if (drive.empty()) return m;
  // The rod: the closed loop's T from the drive, 1 at rest (the loop's integral).
  const auto rod = filtered(drive, dt, [&](double f) { return f > 0.0 ? paths.feedback.at(f) : 1.0; });
  const auto [lo, hi] = std::minmax_element(rod.begin(), rod.end());
  m.rod_min = *lo;
  m.rod_max = *hi;
  m.rod_velocity = k.velocity * peak_rate(rod, dt);
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
