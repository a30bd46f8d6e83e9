#include "tools/iterate/drive_iteration.hpp"

#include <cmath>

#include "tools/iterate/road_target.hpp"

namespace rigctl {

std::string_view to_string(IterationEnd end) {
  switch (end) {
    case IterationEnd::kTolerance: return "tolerance";
    case IterationEnd::kNoImprovement: return "no_improvement";
    case IterationEnd::kMaxIterations: return "max_iterations";
    case IterationEnd::kDriveLimit: return "drive_limit";
    case IterationEnd::kRunEnded: return "run_ended";
  }
  return "?";
}

namespace {

struct Step {
  const DriveInverse& inverse;
  const IterationRig& rig;
  const IterationSettings& settings;
  std::size_t fade;

  // alpha H^-1 x, its moving part faded in and out so that the drive starts
  // and ends at rest; its mean is kept (the rest level moves with it: the
  // wheel's static offset from the rod, the tyre's deflection, is corrected
  // at the ends too).
  std::vector<double> correction(const std::vector<double>& x, const std::vector<double>& gain) const {
    std::vector<double> c = inverse.apply(x, gain);
    double mean = 0.0;
    for (double v : c) mean += v / static_cast<double>(c.size());
    for (double& v : c) v -= mean;
    fade_ends(c, fade);
    for (double& v : c) v += mean;
    return c;
  }

  // The safety check; false (and the outcome's end set) when the drive may not be played.
  bool admit(std::vector<double>& drive, IterationRecord& rec, IterationOutcome& out) const {
    const DriveLimits limits = drive_limits(*rig.config);
    rec.peaks = drive_peaks(*rig.config, drive, rig.operating_point, rig.command_hold);
    const DriveVerdict v = check_drive(rec.peaks, limits, rig.operating_point);
    if (v.ok) return true;
    if (!settings.scale_to_fit || !(v.fit_scale > 0.0)) {
      out.end = IterationEnd::kDriveLimit;
      out.end_detail = "drive " + std::to_string(rec.index) + " not played: " + v.reason;
      return false;
    }
    // Scale a little below the fit so the rounding of the peaks cannot tip
    // it over; again while the valve's hold command (which does not scale)
    // keeps the effort above its limit.
    rec.limited_by = v.reason;
    DriveVerdict now = v;
    for (int attempt = 0; attempt < 10 && !now.ok; ++attempt) {
      const double scale = 0.99 * now.fit_scale;
      rec.drive_scale *= scale;
      scale_drive(drive, rig.operating_point, scale);
      rec.peaks = drive_peaks(*rig.config, drive, rig.operating_point, rig.command_hold);
      now = check_drive(rec.peaks, limits, rig.operating_point);
    }
    if (!now.ok) {
      out.end = IterationEnd::kDriveLimit;
      out.end_detail = "drive " + std::to_string(rec.index) + " cannot be scaled to fit: " + now.reason;
      return false;
    }
    return true;
  }
};

std::vector<double> minus(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

}  // namespace

IterationOutcome iterate_drive(const std::vector<double>& target, const DriveFrf& frf, const IterationRig& rig,
                               const IterationSettings& s) {
  const double dt = rig.config->loop.period_s;
  const DriveInverse inverse(frf, target.size(), dt, s.inverse);
  const Step step{inverse, rig, s, static_cast<std::size_t>(std::llround(s.fade_s / dt))};
  std::vector<double> gain(inverse.bands().size(), 1.0);
  std::vector<double> rest(target.size(), rig.operating_point);
  // First drive: the inverse applied to the target (its deviation from the rest level).
  std::vector<double> drive = rest;
  const auto first = step.correction(minus(target, rest), gain);
  for (std::size_t i = 0; i < drive.size(); ++i) drive[i] += first[i];
  gain.assign(gain.size(), s.initial_gain);

  IterationOutcome out;
  std::vector<double> last_energy;
  for (int k = 1; k <= s.max_iterations; ++k) {
    IterationRecord rec;
    rec.index = k;
    rec.gain = gain;
    if (!step.admit(drive, rec, out)) return out;
    const PlayResult played = rig.play(drive, k);
    if (!played.completed) {
      out.end = IterationEnd::kRunEnded;
      out.end_detail = "drive " + std::to_string(k) + " ended early: " + played.end_reason;
      return out;
    }
    rec.drive = drive;
    rec.response = played.response;
    rec.match = match_metrics(target, rec.response, dt, s.inverse.band_min_hz, s.inverse.band_max_hz);
    out.iterations.push_back(rec);
    if (rig.on_iteration) rig.on_iteration(out.iterations.back());
    const double err = rec.match.rel_rms_percent;
    if (out.iterations.size() > 1 && err >= out.iterations[out.best].match.rel_rms_percent) {
      out.end = IterationEnd::kNoImprovement;
      out.end_detail = "iteration " + std::to_string(k) + " did not lower the error";
      if (!rec.limited_by.empty()) out.end_detail += "; its drive was scaled by " + std::to_string(rec.drive_scale) + " for " + rec.limited_by;
      return out;
    }
    out.best = out.iterations.size() - 1;
    if (err <= s.tolerance_percent) {
      out.end = IterationEnd::kTolerance;
      return out;
    }
    const std::vector<double> error = minus(target, rec.response);
    const std::vector<double> energy = inverse.band_energy(error);
    for (std::size_t b = 0; b < gain.size() && !last_energy.empty(); ++b) {
      if (energy[b] > last_energy[b]) gain[b] *= s.gain_cut;
    }
    last_energy = energy;
    const auto update = step.correction(error, gain);
    for (std::size_t i = 0; i < drive.size(); ++i) drive[i] += update[i];
  }
  out.end = IterationEnd::kMaxIterations;
  if (!out.iterations.empty() && !out.iterations.back().limited_by.empty()) {
    out.end_detail = "the last drive was scaled for " + out.iterations.back().limited_by;
  }
  return out;
}

}  // namespace rigctl
