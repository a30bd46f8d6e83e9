#include "tools/iterate/mimo_iterate_command.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "config/config_reader.hpp"
#include "tools/common/json_text.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/identify/channel_view.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/identify/frf_matrix_file.hpp"
#include "tools/iterate/iteration_files.hpp"
#include "tools/iterate/mimo_drive_player.hpp"
#include "tools/iterate/mimo_drive_safety.hpp"
#include "tools/iterate/target_file.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {

// The band may reach 90 % of the target's Nyquist frequency (as the one-channel iteration's).
constexpr double kTargetNyquistShare = 0.9;

// The rig the drives play on: every channel's PI without a demand
// feedforward (the drive is the feedforward, and the matrix was measured
// without one) and the hidden effects of --effect.
RigConfig rig_config(const IterateOptions& o, RigConfig c) {
  c.controller.pi.velocity_feedforward = 0.0;
  for (auto& ch : c.more_channels) ch.controller.pi.velocity_feedforward = 0.0;
  if (o.effects.empty()) return c;
  if (!is_simulated(c.driver)) throw std::invalid_argument("--effect: only a simulated rig can be given hidden effects");
  const RigEffectGenerator& g = effect_generator(c.rig);
  for (const auto& [cause, level] : o.effects) g.apply(c, cause, level, 0);
  return c;
}

std::string two_digits(int k) { return (k < 10 ? "0" : "") + std::to_string(k); }

void write_records(const std::string& path, const std::string& rig, const std::vector<std::string>& names,
                   const std::vector<const std::vector<double>*>& columns, double dt) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "# rig: " << rig << "\n# source: rigctl iterate\nt";
  for (const auto& n : names) f << "," << n;
  f << "\n" << std::setprecision(10);
  for (std::size_t i = 0; i < columns.front()->size(); ++i) {
    f << static_cast<double>(i) * dt;
    for (const auto* c : columns) f << "," << (*c)[i];
    f << "\n";
  }
  if (!f) throw std::runtime_error("write failed: " + path);
}

struct IterationLine {
  int index = 0;
  std::vector<double> error;  // per channel, relative
  std::vector<ActuatorCheck> checks;
};

std::string summary_json(const IterateOptions& o, const std::vector<std::string>& channels, const FrfMatrixData& m,
                         const MimoInverseSettings& s, const MimoInverseReport& inv, const std::vector<IterationLine>& lines,
                         const MimoIterationResult& r, double tolerance) {
  std::ostringstream j;
  auto list = [&](const std::vector<std::string>& v) {
    std::string t = "[";
    for (std::size_t i = 0; i < v.size(); ++i) t += (i ? ", " : "") + json_string(v[i]);
    return t + "]";
  };
  std::vector<std::string> drives;
  for (const auto& d : m.drives) drives.push_back(d.name);
  j << "{\n  \"config\": " << json_string(o.config_path) << ",\n  \"target\": " << json_string(o.target_path)
    << ",\n  \"channels\": " << list(channels) << ",\n  \"drives\": " << list(drives)
    << ",\n  \"frf\": " << json_string(o.frf_path) << ",\n  \"band_hz\": [" << json_number(s.band_min_hz) << ", "
    << json_number(s.band_max_hz) << "],\n  \"tolerance_percent\": " << json_number(100.0 * tolerance)
    << ",\n  \"inverse\": {\"lines_inverted\": " << inv.lines_inverted << ", \"lines_gated\": " << inv.lines_gated
    << ", \"lines_rank_reduced\": " << inv.lines_rank_reduced << ", \"largest_singular_value\": "
    << json_number(inv.largest_singular_value) << ", \"eps_floor\": " << json_number(inv.eps_floor)
    << ", \"regularisation\": " << json_number(s.regularisation) << ", \"coherence_gate\": " << json_number(s.coherence_gate)
    << "},\n  \"iterations\": [";
  for (std::size_t k = 0; k < lines.size(); ++k) {
    j << (k ? ",\n    " : "\n    ") << "{\"iteration\": " << lines[k].index << ", \"rel_rms_percent\": {";
    for (std::size_t c = 0; c < channels.size(); ++c) j << (c ? ", " : "") << json_string(channels[c]) << ": " << json_number(100.0 * lines[k].error[c]);
    j << "}, \"actuators\": [";
    for (std::size_t a = 0; a < lines[k].checks.size(); ++a) {
      const auto& p = lines[k].checks[a].peaks;
      j << (a ? ", " : "") << "{\"drive_min\": " << json_number(p.min) << ", \"drive_max\": " << json_number(p.max)
        << ", \"rod_min\": " << json_number(p.predicted.rod_min) << ", \"rod_max\": " << json_number(p.predicted.rod_max)
        << ", \"rod_velocity\": " << json_number(p.predicted.rod_velocity) << ", \"valve_effort\": "
        << json_number(p.predicted.valve_effort) << "}";
    }
    j << "]}";
  }
  j << "\n  ],\n  \"end\": " << json_string(r.converged ? "tolerance" : r.stopped.empty() ? "max_iterations" : "stopped")
    << ",\n  \"end_detail\": " << json_string(r.stopped) << "\n}\n";
  return j.str();
}

}  // namespace

std::vector<std::string> split_channel_list(const std::string& text, const std::string& option) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    if (part.empty()) throw std::invalid_argument(option + ": an empty channel name in '" + text + "'");
    out.push_back(part);
  }
  if (out.empty()) throw std::invalid_argument(option + ": no channel given");
  return out;
}

MimoIterateResult run_mimo_iterate(const IterateOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  MimoIterateResult result;
  const std::vector<std::string> channels = split_channel_list(o.channel, "--channel");
  const std::vector<std::string> file_channels =
      o.target_channel.empty() ? channels : split_channel_list(o.target_channel, "--target-channel");
  if (file_channels.size() != channels.size()) {
    throw std::invalid_argument("--target-channel: " + std::to_string(file_channels.size()) + " channels for --channel's " +
                                std::to_string(channels.size()));
  }
  // What the one-channel iteration has and this one has not yet: refused, not ignored.
  if (o.settings.window_s) throw std::invalid_argument("--window: a rig with several drives iterates the whole target (cut it to the part to reproduce)");
  if (o.settings.scale_to_fit) throw std::invalid_argument("--scale: a rig with several drives refuses a drive beyond an actuator's limits; it does not scale it yet");
  if (o.plot) throw std::invalid_argument("--plot: no plot of a multi-channel iteration yet (DIR/iter_NN_response.csv holds each channel and its target)");
  if (!o.model_path.empty()) throw std::invalid_argument("--model: a rig with several channels iterates from a measured FRF matrix (--frf); no model inverse yet");
  if (o.frf_path.empty()) throw std::invalid_argument("--frf: a rig with several channels needs the FRF matrix from `rigctl identify CONFIG --response CHANNEL ...`");
  const RigConfig rig = rig_config(o, load_rig_config(o.config_path, o.case_name));
  const double dt = rig.loop.period_s;
  const FrfMatrixData m = read_frf_matrix_file(o.frf_path);
  if (m.drives.size() != channel_count(rig)) {
    throw std::invalid_argument(o.frf_path + ": " + std::to_string(m.drives.size()) + " drives, the rig has " +
                                std::to_string(channel_count(rig)) + " control channels");
  }
  for (const auto& c : channels) m.response_index(c);  // throws naming the file's responses

  Records targets;
  double file_period = 0.0;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const Target t = read_target(o.target_path, file_channels[c], dt, o.max_length_s);
    if (!targets.empty() && t.values.size() != targets.front().size()) throw std::invalid_argument("--target: channels of different lengths");
    targets.push_back(t.values);
    file_period = t.file_period_s;
  }
  MimoInverseSettings is;
  is.band_min_hz = std::max(o.settings.inverse.band_min_hz, m.frf.frequency_hz.front());
  is.band_max_hz = std::min({o.settings.inverse.band_max_hz, m.frf.frequency_hz.back(), kTargetNyquistShare * 0.5 / file_period});
  if (!(is.band_max_hz > is.band_min_hz)) throw std::invalid_argument("--band: no band left inside the FRF's lines and the target's Nyquist frequency");
  is.coherence_gate = o.settings.inverse.coherence_gate;
  const MimoDriveInverse inverse(m.rows(channels), targets.front().size(), dt, is);
  const MimoInverseReport& inv = inverse.report();
  out << "rigctl iterate: " << channels.size() << " channels of " << o.target_path << " (" << targets.front().size()
      << " samples, " << static_cast<double>(targets.front().size()) * dt << " s) on " << m.drives.size()
      << " drives, band " << is.band_min_hz << "-" << is.band_max_hz << " Hz, inverse from " << o.frf_path << ": "
      << inv.lines_inverted << " lines inverted, " << inv.lines_gated << " gated (multiple coherence < "
      << is.coherence_gate << "), " << inv.lines_rank_reduced << " regularised below eps (per line "
      << is.regularisation << " x its largest singular value, floor " << inv.eps_floor << ")\n";
  out.flush();

  std::filesystem::create_directories(o.out_dir);
  const std::string rig_name(to_string(rig.rig));
  PlaySettings play;
  play.fast = o.fast;
  play.realtime = o.realtime;
  std::vector<std::string> recorded = channels;
  std::vector<IterationLine> lines;
  std::string run_failure;
  MimoIterationHooks hooks;
  std::vector<ActuatorCheck> last_checks;
  hooks.admit = [&](const Records& drives, int) {
    last_checks = check_actuators(rig, m, drives);
    return refusal(last_checks);
  };
  int playing = 0;
  auto absolute = [&](const Records& drives) {
    Records abs = drives;
    for (std::size_t i = 0; i < abs.size(); ++i) {
      for (double& v : abs[i]) v += m.operating_point[i];
    }
    return abs;
  };
  hooks.on_iteration = [&](int k, const Records& drives, const Records& responses, const std::vector<double>& error) {
    const Records abs = absolute(drives);
    std::vector<std::string> names;
    std::vector<const std::vector<double>*> cols;
    for (std::size_t i = 0; i < abs.size(); ++i) {
      names.push_back(m.drives[i].name);
      cols.push_back(&abs[i]);
    }
    write_records(o.out_dir + "/iter_" + two_digits(k) + "_drive.csv", rig_name, names, cols, dt);
    names.clear();
    cols.clear();
    for (std::size_t c = 0; c < channels.size(); ++c) {
      names.push_back(channels[c]);
      names.push_back(channels[c] + "_target");
      cols.push_back(&responses[c]);
      cols.push_back(&targets[c]);
    }
    write_records(o.out_dir + "/iter_" + two_digits(k) + "_response.csv", rig_name, names, cols, dt);
    lines.push_back({k, error, last_checks});
    out << "  iteration " << k << ":" << std::fixed << std::setprecision(2);
    for (std::size_t c = 0; c < channels.size(); ++c) out << " " << channels[c] << " " << 100.0 * error[c] << " %";
    out << " rms;" << std::setprecision(4);
    for (std::size_t a = 0; a < last_checks.size(); ++a) {
      const auto& p = last_checks[a].peaks.predicted;
      out << " actuator " << a + 1 << " rod " << p.rod_min << ".." << p.rod_max << " m, " << p.rod_velocity
          << " m/s, valve " << p.valve_effort << (a + 1 < last_checks.size() ? ";" : "");
    }
    out << " (predicted)\n" << std::defaultfloat;
    out.flush();
  };
  MimoIterationSettings ms;
  ms.max_iterations = o.settings.max_iterations;
  ms.tolerance = o.settings.tolerance_percent / 100.0;
  ms.first_level = o.settings.first_level;
  ms.period_s = dt;
  result.channels = channels;
  result.iteration = iterate_mimo(
      inverse, targets,
      [&](const Records& drives) -> Records {
        ++playing;
        play.csv_path = o.out_dir + "/iter_" + two_digits(playing) + "_run.csv";
        play.log_path = o.out_dir + "/iter_" + two_digits(playing) + "_run.lcm";
        const MimoPlayResult p = play_drives(rig, absolute(drives), m.operating_point, recorded, play, stop, out);
        if (!p.completed) {
          run_failure = p.end_reason;
          return {};
        }
        return p.channels;
      },
      ms, hooks);
  MimoIterationResult& r = result.iteration;
  if (!run_failure.empty()) r.stopped += ": " + run_failure;
  result.summary_path = o.out_dir + "/summary.json";
  write_text_file(result.summary_path, summary_json(o, channels, m, is, inv, lines, r, ms.tolerance));
  out << "  end: " << (r.converged ? "tolerance" : r.stopped.empty() ? "max_iterations" : "stopped (" + r.stopped + ")")
      << "\n  summary: " << result.summary_path << "\n";
  return result;
}

}  // namespace rigctl
