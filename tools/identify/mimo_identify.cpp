#include "tools/identify/mimo_identify.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <span>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/identify/channel_view.hpp"
#include "tools/identify/excitation_profile.hpp"
#include "tools/identify/identify_analysis.hpp"
#include "tools/identify/identify_run_defaults.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {


void add_unique(std::vector<std::string>& names, const std::string& n) {
  if (std::find(names.begin(), names.end(), n) == names.end()) names.push_back(n);
}

void describe_plan(const MimoIdentifyPlan& p, double dt, std::ostream& out) {
  const double period = static_cast<double>(p.period_ticks) * dt;
  out << "rigctl identify: orthogonal multisines on " << p.drives.size() << " drives, " << p.band_min_hz << "-"
      << p.band_max_hz << " Hz (" << p.lines.size() << " lines every " << 1.0 / period << " Hz), " << p.realisations
      << " realisations of " << p.settle_periods + 1 << " periods of " << period << " s\n";
  for (std::size_t i = 0; i < p.channels.size(); ++i) {
    const IdentifyPlan& c = p.channels[i];
    out << "  " << p.drives[i] << " about " << c.config.controller.feedback << " = " << c.operating_point
        << ": amplitude " << c.excitation.amplitude << " (clamp " << c.clamp.limit << " from " << c.clamp.reason << ")\n";
  }
  out.flush();
}

void describe_matrix(const FrfMatrixData& m, std::ostream& out) {
  const MimoFrf& f = m.frf;
  out << "  FRF matrix: " << m.responses.size() << " responses x " << m.drives.size() << " drives, "
      << f.frequency_hz.size() << " lines, " << f.averages << " averages; input condition up to " << std::setprecision(3)
      << *std::max_element(f.input_condition.begin(), f.input_condition.end()) << "\n";
  for (std::size_t j = 0; j < m.responses.size(); ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    double lo = 1.0, hi = 0.0;
    for (const auto& c : f.multiple_coherence) {
      lo = std::min(lo, c(jj));
      hi = std::max(hi, c(jj));
    }
    out << "  " << m.responses[j].name << ": multiple coherence " << lo << " to " << hi << "; partial coherence, least:";
    for (std::size_t i = 0; i < m.drives.size(); ++i) {
      double least = 1.0;
      for (const auto& p : f.partial_coherence) least = std::min(least, p(jj, static_cast<Eigen::Index>(i)));
      out << " " << m.drives[i].name << " " << least;
    }
    out << "\n";
  }
  out << std::defaultfloat;
}

}  // namespace

MimoIdentifyPlan plan_mimo_identification(const RigConfig& config, const IdentifySettings& s) {
  if (s.excitation && *s.excitation != ExcitationKind::kMultisine) {
    throw std::invalid_argument("--excitation: a rig with several drives is excited by orthogonal multisines (multisine) only, not " +
                                std::string(to_string(*s.excitation)));
  }
  MimoIdentifyPlan p;
  p.config = config;
  const std::size_t n = channel_count(config);
  const std::string setpoint = setpoint_name_for(config.rig);
  for (std::size_t i = 0; i < n; ++i) {
    RigConfig one = channel_view(config, i);
    one.file = config.file + (i == 0 ? "" : ": channels[" + std::to_string(i) + "]");
    p.channels.push_back(plan_identification(one, s));
    const ControllerConfig& adapted = p.channels.back().config.controller;
    if (i == 0) {
      p.config.controller = adapted;
      p.config.safety = p.channels.back().config.safety;  // every trip an interlock
    } else {
      p.config.more_channels[i - 1].controller = adapted;
    }
    p.drives.push_back(channel_setpoint_name(setpoint, i));
  }
  for (const auto& c : p.channels) add_unique(p.responses, c.config.controller.feedback);
  for (const auto& c : p.channels) add_unique(p.responses, c.config.controller.output);
  for (const auto& extra : s.extra_responses) add_unique(p.responses, extra);

  const ExcitationSpec& e = p.channels.front().excitation;
  if (!(e.band_min_hz > 0.0 && e.band_max_hz > e.band_min_hz)) {
    throw ConfigError(config.file + ": identify.band_hz: needs 0 < low < high");
  }
  p.band_min_hz = e.band_min_hz;
  p.band_max_hz = e.band_max_hz;
  p.period_ticks = segment_ticks(e.resolution_hz, e.period_s);
  const double period_s = static_cast<double>(p.period_ticks) * e.period_s;
  for (std::size_t k = 1; 2 * k < p.period_ticks; ++k) {
    const double f = static_cast<double>(k) / period_s;
    if (f >= e.band_min_hz - 1e-9 && f <= e.band_max_hz + 1e-9) p.lines.push_back(k);
  }
  if (p.lines.empty()) throw ConfigError(config.file + ": identify.band_hz: no line of a " + std::to_string(period_s) + " s period in the band");
  const auto by_duration = static_cast<std::size_t>(std::lround(e.duration_s / ((p.settle_periods + 1) * period_s)));
  p.realisations = std::max(2 * n, by_duration);
  p.settle_s = p.channels.front().settle_s;
  return p;
}

MimoIdentifyResult run_mimo_identify(const IdentifyOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  MimoIdentifyResult result;
  result.plan = plan_mimo_identification(load_rig_config(o.config_path, o.case_name), o.settings);
  const MimoIdentifyPlan& plan = result.plan;
  const double dt = plan.config.loop.period_s;
  const std::size_t n_x = plan.drives.size();
  describe_plan(plan, dt, out);

  // One set of phases per drive, one amplitude: each drive's record is then
  // scaled to its own channel's amplitude.
  const MimoExcitation e = orthogonal_multisines(plan.lines, plan.period_ticks, n_x, plan.realisations, 1.0, plan.config.seed);
  std::vector<std::vector<double>> played = played_records(e, plan.settle_periods);
  for (std::size_t i = 0; i < n_x; ++i) {
    for (double& v : played[i]) v *= plan.channels[i].excitation.amplitude;
  }
  // The excitations start together: each channel's hold after its lead-in
  // is lengthened to the longest lead-in.
  std::vector<LeadIn> leads;
  for (const auto& c : plan.channels) leads.push_back(lead_in_to(c.config, c.operating_point));
  const AlignedExcitation aligned(std::move(leads), played, plan.settle_s, dt, kIdentifyTailS);
  auto profile = [&](std::size_t i) { return aligned.profile(i); };

  RunOptions ro;
  ro.config_path = o.config_path;
  ro.case_name = o.case_name;
  ro.fast = o.fast;
  ro.realtime = o.realtime;
  ro.log_path = o.log_path;
  ro.csv_path = o.csv_path.empty() ? identify_default_csv_path(o.out_path) : o.csv_path;
  ro.profile_override = [&] { return profile(0); };
  ro.more_profile_override = [&](std::size_t i) { return profile(i); };
  result.run = run_rig(plan.config, ro, stop, out);
  if (result.run.loop.final_state == RigState::kFaulted || stop.load()) {
    result.aborted = true;
    result.abort_reason = stop.load() ? "stop requested" : result.run.end_reason;
    out << "  identification aborted: " << result.abort_reason << "; every valve is at null, no FRF written\n";
    return result;
  }

  RunFileOptions columns;
  columns.required = plan.drives;
  columns.required.insert(columns.required.end(), plan.responses.begin(), plan.responses.end());
  const RunFile run = read_run_file(ro.csv_path, columns);
  const double op0 = plan.channels.front().operating_point;
  std::vector<double> deviation0 = played[0];
  const auto settle_ticks = static_cast<std::size_t>(std::lround(plan.settle_s / dt));
  const std::size_t start = find_excitation_start(run.col(plan.drives[0]), op0, deviation0, settle_ticks);
  const std::size_t length = played[0].size();
  auto slice = [&](const std::string& name, double minus) {
    const auto& y = run.col(name);
    std::vector<double> out_(y.begin() + static_cast<std::ptrdiff_t>(start), y.begin() + static_cast<std::ptrdiff_t>(start + length));
    for (double& v : out_) v -= minus;
    return out_;
  };
  std::vector<std::vector<double>> drives, responses;
  for (std::size_t i = 0; i < n_x; ++i) drives.push_back(slice(plan.drives[i], plan.channels[i].operating_point));
  for (const auto& r : plan.responses) responses.push_back(slice(r, 0.0));
  drives = steady_periods(drives, e, plan.settle_periods);
  responses = steady_periods(responses, e, plan.settle_periods);

  FrfMatrixData& m = result.matrix;
  const WelchSettings welch{plan.period_ticks, plan.period_ticks, SpectralWindow::kRectangular, 1.0 / dt};
  m.frf = estimate_mimo_frf({drives.begin(), drives.end()}, {responses.begin(), responses.end()}, welch, plan.band_min_hz,
                            plan.band_max_hz, plan.lines);
  m.rig = std::string(to_string(plan.config.rig));
  m.config = o.config_path;
  m.run_log = result.run.log_path;
  m.sample_rate_hz = 1.0 / dt;
  for (std::size_t i = 0; i < n_x; ++i) {
    const auto& c = plan.channels[i];
    m.drives.push_back({plan.drives[i], frf_channels(c.config, {c.config.controller.feedback})[0].unit});
    m.operating_point.push_back(c.operating_point);
    m.excitation.amplitude.push_back(c.excitation.amplitude);
  }
  m.responses = frf_channels(plan.config, plan.responses);
  for (const auto& r : responses) {
    double s = 0.0;
    for (double v : r) s += v;
    m.response_mean.push_back(s / static_cast<double>(r.size()));
  }
  FrfMatrixExcitation& x = m.excitation;
  x.band_min_hz = plan.band_min_hz;
  x.band_max_hz = plan.band_max_hz;
  x.realisations = plan.realisations;
  x.period_s = static_cast<double>(plan.period_ticks) * dt;
  x.settle_periods = plan.settle_periods;
  x.seed = plan.config.seed;
  x.start_s = run.t[start];
  x.end_s = run.t[start] + static_cast<double>(length) * dt;
  describe_matrix(m, out);
  write_frf_matrix_file(m, o.out_path);
  out << "  frf: " << o.out_path << "\n";
  return result;
}

}  // namespace rigctl
