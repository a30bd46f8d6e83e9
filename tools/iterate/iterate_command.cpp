#include "tools/iterate/iterate_command.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <numeric>

#include "config/config_reader.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/identify/identify_command.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/identify/plant_linearisation.hpp"
#include "tools/iterate/diagnosis_model.hpp"
#include "tools/iterate/iteration_files.hpp"
#include "tools/iterate/mimo_iterate_command.hpp"
#include "tools/iterate/target_file.hpp"
#include "tools/iterate/test_window.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {

// The model's line spacing: finer than the quarter car's sharpest feature
// (the wheel hop, ~24 Hz with 0.3 damping: a 15 Hz wide peak).
constexpr double kModelStepHz = 0.05;
// The band may reach 90 % of the target's Nyquist frequency: the
// resampler's low-pass starts there (resample.hpp).
constexpr double kTargetNyquistShare = 0.9;

// The rig the drives play on: the config's, its PI without a demand
// feedforward (the drive is the feedforward here, and the FRF the inverse
// comes from, measured by identify or computed from the model, is the
// feedback loop's: with a feedforward in, the played loop would not be the
// inverted one), and the hidden effects of --effect.
RigConfig rig_config(const IterateOptions& o, RigConfig c) {
  c.controller.pi.velocity_feedforward = 0.0;
  if (o.effects.empty()) return c;
  if (!is_simulated(c.driver)) throw std::invalid_argument("--effect: only a simulated rig can be given hidden effects");
  const RigEffectGenerator& g = effect_generator(c.rig);
  for (const auto& [cause, level] : o.effects) g.apply(c, cause, level, 0);
  return c;
}

// The inverse's FRF (drive -> channel) and the prediction's paths (drive ->
// rod, drive -> command), all from one source: the measured file, the
// diagnosis's model or the config's own.
void set_frfs(const IterateOptions& o, const RigConfig& nominal, double op, double band_max_hz, IterationRig& rig) {
  if (!o.frf_path.empty() && !o.model_path.empty()) throw std::invalid_argument("give --frf or --model, not both");
  if (!o.frf_path.empty()) {
    const FrfData frf = read_frf_file(o.frf_path);
    rig.channel = drive_frf_from_file(frf, o.channel, o.frf_path);
    rig.paths = loop_paths_from_file(frf, nominal.controller.feedback, o.frf_path);
    return;
  }
  const auto freqs = model_frequencies(kModelStepHz, band_max_hz + 1.0);
  const bool diagnosis = !o.model_path.empty();
  const RigConfig model = diagnosis ? diagnosis_model_config(nominal, o.model_path) : nominal;
  const std::string source = diagnosis ? "diagnosis model " + o.model_path : "nominal model";
  rig.channel = drive_frf_from_model(model, o.channel, op, freqs, source);
  rig.paths = loop_paths_from_model(model, op, freqs, source);
}

// The target's own Nyquist frequency bounds the band: content it cannot
// hold is not asked of the rig.
void limit_band(InverseSettings& band, const Target& t, std::ostream& out) {
  const double top = kTargetNyquistShare * 0.5 / t.file_period_s;
  if (band.band_max_hz <= top) return;
  out << "  the band ends at " << top << " Hz, 90 % of the target's Nyquist frequency (" << 0.5 / t.file_period_s
      << " Hz), not at " << band.band_max_hz << " Hz\n";
  band.band_max_hz = top;
  if (band.band_min_hz >= top) throw std::invalid_argument("--band: the target's Nyquist frequency leaves no band above " + std::to_string(band.band_min_hz) + " Hz");
}

double command_hold(const RigConfig& c, double op) {
  if (c.rig != RigKind::kQuarterCar) return 0.0;
  return linearise_quarter_car(c.quarter_car, op, {c.controller.feedback}).command;
}

void report(const IterationRecord& r, std::ostream& out) {
  const PredictedMotion& p = r.peaks.predicted;
  out << "  iteration " << r.index << ": error " << std::fixed << std::setprecision(2) << r.match.rel_rms_percent
      << " % rms over the test part (" << r.match.whole_rel_rms_percent << " % whole), trac " << std::setprecision(4)
      << r.match.trac << ", peak error " << std::setprecision(2) << r.match.peak_error * 1e3 << " mm; rod "
      << std::setprecision(3) << r.measured.rod_velocity << " m/s (predicted " << p.rod_velocity << "), valve "
      << r.measured.valve_effort << " (predicted " << p.valve_effort << ")";
  if (r.drive_scale < 1.0) out << " (scaled x" << r.drive_scale << ")";
  out << "\n" << std::defaultfloat;
  out.flush();
}

void plot_iterations(const std::string& dir) {
  const char* env = std::getenv("RIGCTL_PLOTS_DIR");
  const std::string script = std::string(env != nullptr ? env : RIGCTL_PLOTS_DIR) + "/plot_iteration.py";
  const std::string cmd = "/usr/bin/python3 '" + script + "' '" + dir + "'";
  if (std::system(cmd.c_str()) != 0) {
    throw std::runtime_error("plotting failed (" + cmd + "); matplotlib comes with tools/scripts/setup.sh --plots");
  }
}

IterationSummary summary_of(const IterateOptions& o, const RigConfig& rig, const DriveFrf& frf, double op,
                            const IterationSettings& s, const Target& target) {
  IterationSummary summary;
  summary.config = o.config_path;
  summary.target = o.target_path;
  summary.target_channel = target.channel;
  summary.target_period_s = target.file_period_s;
  summary.target_start_s = target.start_s;
  summary.first_level = s.first_level;
  summary.max_growth = s.max_growth;
  summary.period_s = rig.loop.period_s;
  summary.channel = o.channel;
  summary.frf_source = frf.source;
  summary.rig = std::string(to_string(rig.rig));
  summary.operating_point = op;
  summary.band_min_hz = s.inverse.band_min_hz;
  summary.band_max_hz = s.inverse.band_max_hz;
  summary.tolerance_percent = s.tolerance_percent;
  summary.limits = drive_limits(rig);
  return summary;
}

}  // namespace

IterateResult run_iterate(const IterateOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  if (o.channel.empty()) throw std::invalid_argument("--channel: the target channel is required");
  const RigConfig nominal = load_rig_config(o.config_path, o.case_name);
  if (!nominal.more_channels.empty()) {
    // Several drives: the MIMO iteration (mimo_iterate_command.hpp).
    const MimoIterateResult m = run_mimo_iterate(o, stop, out);
    IterateResult r;
    r.summary_path = m.summary_path;
    r.outcome.end = m.iteration.converged ? IterationEnd::kTolerance
                    : m.iteration.stopped.find("not played") != std::string::npos ? IterationEnd::kDriveLimit
                    : !m.iteration.stopped.empty()                              ? IterationEnd::kRunEnded
                                                                                : IterationEnd::kMaxIterations;
    r.outcome.end_detail = m.iteration.stopped;
    return r;
  }
  const RigConfig rig = rig_config(o, nominal);
  const double dt = rig.loop.period_s;
  IterationSettings s = o.settings;
  const auto& band = s.inverse;
  if (!(band.band_min_hz > 0.0 && band.band_max_hz > band.band_min_hz && band.band_max_hz <= 0.5 / dt)) {
    throw std::invalid_argument("--band: needs 0 < low < high <= " + std::to_string(0.5 / dt) +
                                " Hz (half the loop's rate), got " + std::to_string(band.band_min_hz) + " " +
                                std::to_string(band.band_max_hz));
  }
  const Target target = read_target(o.target_path, o.target_channel.empty() ? o.channel : o.target_channel, dt, o.max_length_s);
  limit_band(s.inverse, target, out);
  const TestWindow window = test_window_of(target.values, dt, s);
  // The operating point: the test part's mean, where the rig spends the test
  // (a lead-in from home would pull the whole record's mean down).
  const double op = std::accumulate(target.values.begin() + static_cast<std::ptrdiff_t>(window.begin),
                                    target.values.begin() + static_cast<std::ptrdiff_t>(window.end), 0.0) /
                    static_cast<double>(window.end - window.begin);
  IterationRig iteration_rig;
  set_frfs(o, nominal, op, s.inverse.band_max_hz, iteration_rig);
  std::filesystem::create_directories(o.out_dir);

  IterationSummary summary = summary_of(o, rig, iteration_rig.channel, op, s, target);
  out << "rigctl iterate: " << target.channel << " of " << o.target_path << " (" << target.values.size() << " samples, "
      << static_cast<double>(target.values.size()) * dt << " s) as " << o.channel << " about " << op
      << ", test part " << static_cast<double>(window.begin) * dt << "-" << static_cast<double>(window.end) * dt
      << " s (" << window.source << "), inverse from " << iteration_rig.channel.source << "\n";

  PlaySettings play;
  play.operating_point = op;
  play.fast = o.fast;
  play.realtime = o.realtime;
  const std::string setpoint = setpoint_name_for(rig.rig);
  const std::string frf_unit = frf_channels(rig, {o.channel})[0].unit;
  iteration_rig.config = &rig;
  iteration_rig.operating_point = op;
  // From the config as given: a rig's hidden effects are not known to the one who runs it.
  iteration_rig.command_hold = command_hold(nominal, op);
  iteration_rig.play = [&](const std::vector<double>& drive, int k) {
    play.operating_point = drive.front();  // the drive's rest level: the lead-in goes there
    play.csv_path = o.out_dir + "/iter_" + (k < 10 ? "0" : "") + std::to_string(k) + "_run.csv";
    play.log_path = o.out_dir + "/iter_" + (k < 10 ? "0" : "") + std::to_string(k) + "_run.lcm";
    return play_drive(rig, drive, o.channel, play, stop, out);
  };
  iteration_rig.on_iteration = [&](const IterationRecord& r) {
    write_drive_file(iteration_file(o.out_dir, r.index, "drive"), setpoint, r.drive, dt, summary.rig);
    write_response_file(iteration_file(o.out_dir, r.index, "response"), o.channel, r.response, target.values, dt, summary.rig);
    write_iteration_rpc3(o.out_dir, r.index, setpoint, o.channel, frf_unit, r, target.values, dt);
    report(r, out);
  };
  IterateResult result;
  result.outcome = iterate_drive(target.values, iteration_rig, s);
  summary.lines_gated = DriveInverse(iteration_rig.channel, target.values.size(), dt, s.inverse).lines_gated();
  result.summary_path = o.out_dir + "/summary.json";
  write_text_file(result.summary_path, summary_json(summary, result.outcome));
  out << "  end: " << to_string(result.outcome.end)
      << (result.outcome.end_detail.empty() ? "" : " (" + result.outcome.end_detail + ")") << "\n  summary: "
      << result.summary_path << "\n";
  if (o.plot && !result.outcome.iterations.empty()) {
    plot_iterations(o.out_dir);
    out << "  plot: " << o.out_dir << "/iterations.png\n";
  }
  return result;
}

}  // namespace rigctl
