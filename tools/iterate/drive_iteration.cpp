#include "tools/iterate/drive_iteration.hpp"

#include <cmath>

#include "tools/iterate/gain_adaptation.hpp"
#include "tools/iterate/spectrum.hpp"

namespace rigctl {

std::string_view to_string(IterationEnd end) {
  switch (end) {
    case IterationEnd::kTolerance: return "tolerance";
    case IterationEnd::kNoImprovement: return "no_improvement";
    case IterationEnd::kMaxIterations: return "max_iterations";
    case IterationEnd::kDriveLimit: return "drive_limit";
    case IterationEnd::kDriveGrowth: return "drive_growth";
    case IterationEnd::kRunEnded: return "run_ended";
  }
  return "?";
}

namespace {

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

std::vector<double> minus(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

std::vector<double> minus(const std::vector<double>& a, double b) {
  std::vector<double> d(a);
  for (double& v : d) v -= b;
  return d;
}

double rms(const std::vector<double>& x) {
  double s = 0.0;
  for (double v : x) s += v * v;
  return x.empty() ? 0.0 : std::sqrt(s / static_cast<double>(x.size()));
}

// What one iteration needs beside the settings: the inverse, the rig, the
// correction's weight along the record.
struct Step {
  const DriveInverse& inverse;
  const IterationRig& rig;
  const IterationSettings& settings;
  std::vector<double> weight;
  ValveLaw law;

  double dt() const { return rig.config->loop.period_s; }

  // drive + w (x - drive): x where the correction counts, the drive at the holds.
  std::vector<double> blend(const std::vector<double>& drive, const std::vector<double>& x) const {
    std::vector<double> out(drive);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] += weight[i] * (x[i] - drive[i]);
    return out;
  }

  // The target's deviation from the operating point: below the band as it
  // is (the loop follows slow motion; the lead-in and lead-out are the
  // target's own), in the band through the inverse at `level`; blended
  // into the target itself at the holds.
  std::vector<double> first_drive(const std::vector<double>& target, double level) const {
    const double op = rig.operating_point;
    const std::vector<double> dev = minus(target, op);
    const std::vector<double> above = band_passed(dev, dt(), settings.inverse.band_min_hz, 0.5 / dt());
    std::vector<double> in_band(inverse.bands().size(), 1.0);
    in_band[0] = 0.0;  // band 0 lies below the band
    const std::vector<double> inv = inverse.apply(dev, in_band);
    std::vector<double> full(target.size());
    for (std::size_t i = 0; i < full.size(); ++i) full[i] = op + dev[i] - above[i] + level * inv[i];
    return blend(target, full);
  }

  std::vector<double> updated(const std::vector<double>& drive, const std::vector<double>& error,
                              const std::vector<double>& gain) const {
    const std::vector<double> c = inverse.apply(error, gain);
    std::vector<double> out(drive);
    for (std::size_t i = 0; i < out.size(); ++i) out[i] += weight[i] * c[i];
    return out;
  }

  double band_rms(const std::vector<double>& drive) const {
    return rms(band_passed(drive, dt(), settings.inverse.band_min_hz, settings.inverse.band_max_hz));
  }

  DrivePeaks peaks(const std::vector<double>& drive, const PredictionCorrection& k) const {
    return drive_peaks(drive, rig.operating_point, dt(),
                       predict_motion(rig.paths, drive, dt(), rig.command_hold, law, k));
  }

  bool admit(std::vector<double>& drive, IterationRecord& rec, IterationOutcome& out) const;
};

// The safety check; false (and the outcome's end set) when the drive may not be played.
bool Step::admit(std::vector<double>& drive, IterationRecord& rec, IterationOutcome& out) const {
  const DriveLimits limits = drive_limits(*rig.config);
  rec.peaks = peaks(drive, rec.correction);
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
    rec.peaks = peaks(drive, rec.correction);
    now = check_drive(rec.peaks, limits, rig.operating_point);
  }
  if (!now.ok) {
    out.end = IterationEnd::kDriveLimit;
    out.end_detail = "drive " + std::to_string(rec.index) + " cannot be scaled to fit: " + now.reason;
    return false;
  }
  return true;
}

// Before anything is played: the target's drive at full level must be one
// the rig can play (the reduced first pass would pass where the later
// drives cannot).
bool admit_full_level(const Step& step, const std::vector<double>& target, IterationOutcome& out) {
  if (step.settings.scale_to_fit || step.settings.first_level >= 1.0) return true;
  const DrivePeaks k = step.peaks(step.first_drive(target, 1.0), PredictionCorrection{});
  const DriveVerdict v = check_drive(k, drive_limits(*step.rig.config), step.rig.operating_point);
  if (v.ok) return true;
  out.end = IterationEnd::kDriveLimit;
  out.end_detail = "drive 1 not played: the target's drive at full level: " + v.reason;
  return false;
}

// After a played drive: the gain per band from the rig's answer against the
// model's prediction for the drive's change (the whole drive the first time).
void adapt(const Step& step, const IterationRecord& rec, const IterationRecord* last, std::vector<double>& gain,
           IterationOutcome& out) {
  const double op = step.rig.operating_point;
  const std::vector<double> dd = last ? minus(rec.drive, last->drive) : minus(rec.drive, op);
  const std::vector<double> dy = last ? minus(rec.response, last->response) : minus(rec.response, op);
  const std::vector<double> predicted = filtered(dd, step.dt(), [&](double f) { return step.rig.channel.at(f); });
  const GainUpdate u = adapt_gain(step.inverse.band_ratio(dy, predicted), step.inverse.band_energy(predicted), gain);
  gain = u.gain;
  const auto& edges = step.inverse.bands().edges_hz;
  for (std::size_t b : u.gated) out.gated_bands_hz.emplace_back(edges[b], edges[b + 1]);
}

}  // namespace

TestWindow test_window_of(const std::vector<double>& target, double dt, const IterationSettings& s) {
  if (s.window_s) return window_from_times(s.window_s->first, s.window_s->second, target.size(), dt);
  return find_test_window(target, dt);
}

IterationOutcome iterate_drive(const std::vector<double>& target, const IterationRig& rig, const IterationSettings& s) {
  const double dt = rig.config->loop.period_s;
  IterationOutcome out;
  out.window = test_window_of(target, dt, s);
  const DriveInverse inverse(rig.channel, target.size(), dt, s.inverse);
  const Step step{inverse, rig, s, correction_weight(out.window, target, dt, s.lead_s, s.fade_s),
                  valve_law(*rig.config, rig.command_hold)};
  if (!admit_full_level(step, target, out)) return out;
  std::vector<double> gain(inverse.bands().size(), s.initial_gain);
  std::vector<double> drive = step.first_drive(target, s.first_level);
  PredictionCorrection correction;
  std::vector<double> last_energy;
  for (int k = 1; k <= s.max_iterations; ++k) {
    IterationRecord rec;
    rec.index = k;
    rec.gain = gain;
    rec.level = k == 1 ? s.first_level : 1.0;
    rec.correction = correction;
    if (!out.iterations.empty()) {
      rec.growth = step.band_rms(drive) / step.band_rms(out.iterations.back().drive);
      if (rec.growth > s.max_growth) {
        out.end = IterationEnd::kDriveGrowth;
        out.end_detail = "drive " + std::to_string(k) + " not played: its content in the band grew x" + fmt(rec.growth) +
                         " over drive " + std::to_string(k - 1) + "'s (at most x" + fmt(s.max_growth) + ", --max-growth)";
        return out;
      }
    }
    if (!step.admit(drive, rec, out)) return out;
    const PlayResult played = rig.play(drive, k);
    if (!played.completed) {
      out.end = IterationEnd::kRunEnded;
      out.end_detail = "drive " + std::to_string(k) + " ended early: " + played.end_reason;
      return out;
    }
    rec.drive = drive;
    rec.response = played.response;
    rec.measured = measured_motion(played.feedback, played.command, dt, s.inverse.band_max_hz);
    correction = correction_from(step.peaks(drive, PredictionCorrection{}).predicted, rec.measured);
    rec.match = match_metrics(target, rec.response, dt, s.inverse.band_min_hz, s.inverse.band_max_hz, out.window);
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
    const IterationRecord* last = out.iterations.size() > 1 ? &out.iterations[out.iterations.size() - 2] : nullptr;
    adapt(step, out.iterations.back(), last, gain, out);
    const std::vector<double> error = minus(target, rec.response);
    const std::vector<double> energy = inverse.band_energy(error);
    for (std::size_t b = 0; b < gain.size() && !last_energy.empty(); ++b) {
      if (energy[b] > last_energy[b]) gain[b] *= s.gain_cut;
    }
    last_energy = energy;
    drive = step.updated(drive, error, gain);
  }
  out.end = IterationEnd::kMaxIterations;
  if (!out.iterations.empty() && !out.iterations.back().limited_by.empty()) {
    out.end_detail = "the last drive was scaled for " + out.iterations.back().limited_by;
  }
  return out;
}

}  // namespace rigctl
