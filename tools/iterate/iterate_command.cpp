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
#include "tools/iterate/target_file.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {

// The model's line spacing: finer than the quarter car's sharpest feature
// (the wheel hop, ~24 Hz with 0.3 damping: a 15 Hz wide peak).
constexpr double kModelStepHz = 0.05;

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

DriveFrf drive_frf(const IterateOptions& o, const RigConfig& nominal, double op, double band_max_hz) {
  if (!o.frf_path.empty() && !o.model_path.empty()) throw std::invalid_argument("give --frf or --model, not both");
  if (!o.frf_path.empty()) return drive_frf_from_file(read_frf_file(o.frf_path), o.channel, o.frf_path);
  const auto freqs = model_frequencies(kModelStepHz, band_max_hz + 1.0);
  if (!o.model_path.empty()) {
    const RigConfig model = diagnosis_model_config(nominal, o.model_path);
    return drive_frf_from_model(model, o.channel, op, freqs, "diagnosis model " + o.model_path);
  }
  return drive_frf_from_model(nominal, o.channel, op, freqs, "nominal model");
}

double command_hold(const RigConfig& c, double op) {
  if (c.rig != RigKind::kQuarterCar) return 0.0;
  return linearise_quarter_car(c.quarter_car, op, {c.controller.feedback}).command;
}

void report(const IterationRecord& r, std::ostream& out) {
  out << "  iteration " << r.index << ": error " << std::fixed << std::setprecision(2) << r.match.rel_rms_percent
      << " % rms, trac " << std::setprecision(4) << r.match.trac << ", peak error " << std::setprecision(2)
      << r.match.peak_error * 1e3 << " mm; drive peak " << r.peaks.displacement * 1e3 << " mm, "
      << r.peaks.velocity << " m/s, valve " << std::setprecision(3) << r.peaks.valve_effort;
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

IterationSummary summary_of(const IterateOptions& o, const RigConfig& rig, const DriveFrf& frf, double op) {
  IterationSummary summary;
  summary.config = o.config_path;
  summary.target = o.target_path;
  summary.channel = o.channel;
  summary.frf_source = frf.source;
  summary.rig = std::string(to_string(rig.rig));
  summary.operating_point = op;
  summary.band_min_hz = o.settings.inverse.band_min_hz;
  summary.band_max_hz = o.settings.inverse.band_max_hz;
  summary.tolerance_percent = o.settings.tolerance_percent;
  summary.limits = drive_limits(rig);
  return summary;
}

}  // namespace

IterateResult run_iterate(const IterateOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  if (o.channel.empty()) throw std::invalid_argument("--channel: the target channel is required");
  const RigConfig nominal = load_rig_config(o.config_path, o.case_name);
  const RigConfig rig = rig_config(o, nominal);
  const double dt = rig.loop.period_s;
  const auto& band = o.settings.inverse;
  if (!(band.band_min_hz > 0.0 && band.band_max_hz > band.band_min_hz && band.band_max_hz <= 0.5 / dt)) {
    throw std::invalid_argument("--band: needs 0 < low < high <= " + std::to_string(0.5 / dt) +
                                " Hz (half the loop's rate), got " + std::to_string(band.band_min_hz) + " " +
                                std::to_string(band.band_max_hz));
  }
  const std::vector<double> target = read_target(o.target_path, o.channel, dt);
  const double op = std::accumulate(target.begin(), target.end(), 0.0) / static_cast<double>(target.size());
  const IterationSettings& s = o.settings;
  const DriveFrf frf = drive_frf(o, nominal, op, s.inverse.band_max_hz);
  std::filesystem::create_directories(o.out_dir);

  IterationSummary summary = summary_of(o, rig, frf, op);
  out << "rigctl iterate: " << o.channel << " of " << o.target_path << " (" << target.size() << " samples, "
      << static_cast<double>(target.size()) * dt << " s) about " << op << ", inverse from " << frf.source << "\n";

  PlaySettings play;
  play.operating_point = op;
  play.fast = o.fast;
  play.realtime = o.realtime;
  const std::string setpoint = setpoint_name_for(rig.rig);
  const std::string frf_unit = frf_channels(rig, {o.channel})[0].unit;
  IterationRig iteration_rig;
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
    write_response_file(iteration_file(o.out_dir, r.index, "response"), o.channel, r.response, target, dt, summary.rig);
    write_iteration_rpc3(o.out_dir, r.index, setpoint, o.channel, frf_unit, r, target, dt);
    report(r, out);
  };
  IterateResult result;
  result.outcome = iterate_drive(target, frf, iteration_rig, s);
  summary.lines_gated = DriveInverse(frf, target.size(), dt, s.inverse).lines_gated();
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
