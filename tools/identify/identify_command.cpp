#include "tools/identify/identify_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <sys/wait.h>

#include "config/config_reader.hpp"
#include "tools/identify/excitation_profile.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/identify/identify_analysis.hpp"
#include "tools/identify/mimo_identify.hpp"
#include "tools/identify/plant_linearisation.hpp"
#include "tools/identify/identify_run_defaults.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {


std::unique_ptr<SetpointProfile> excitation_profile(const IdentifyPlan& plan, const Excitation& e) {
  return std::make_unique<ExcitationProfile>(lead_in_to(plan.config, plan.operating_point), plan.settle_s, e.values,
                                             plan.config.loop.period_s, kIdentifyTailS);
}

void describe_plan(const IdentifyPlan& plan, std::ostream& out) {
  const auto& e = plan.excitation;
  out << "rigctl identify: " << to_string(e.kind) << " " << e.band_min_hz << "-" << e.band_max_hz << " Hz, "
      << e.duration_s << " s about " << plan.config.controller.feedback << " = " << plan.operating_point << "\n"
      << "  amplitude " << e.amplitude << " (requested "
      << (plan.amplitude_requested > 0.0 ? std::to_string(plan.amplitude_requested) : std::string("none"))
      << ", clamp " << plan.clamp.limit << " from " << plan.clamp.reason << ")\n";
  out.flush();
}

// Largest |dB| and |deg| difference between the measured plant and the
// model where the coherence is at least `min_coherence`.
void describe_frf(const FrfData& f, std::ostream& out) {
  out << "  FRF: " << f.frequency_hz.size() << " frequencies, " << f.estimation.averages << " averages ("
      << f.estimation.window << " window, " << f.estimation.segment_s << " s segments)\n";
  for (const auto& g : f.plant) {
    const auto [lo, hi] = std::minmax_element(g.coherence.begin(), g.coherence.end());
    out << "  plant " << f.command.name << " -> " << g.response << ": coherence " << std::setprecision(3) << *lo
        << " to " << *hi;
    if (const FrfCurve* m = f.model_of(g.response)) {
      double db = 0.0, deg = 0.0;
      for (std::size_t i = 0; i < g.value.size(); ++i) {
        if (g.coherence[i] < 0.9) continue;
        const std::complex<double> ratio = g.value[i] / m->value[i];
        db = std::max(db, std::abs(20.0 * std::log10(std::abs(ratio))));
        deg = std::max(deg, std::abs(std::arg(ratio)) * 180.0 / std::numbers::pi);
      }
      out << "; against the plant's linearisation (coherence >= 0.9): within " << db << " dB, " << deg << " deg";
    }
    out << "\n";
  }
}

}  // namespace

std::vector<FrfChannel> frf_channels(const RigConfig& c, const std::vector<std::string>& names) {
  const auto plant = make_plant(c);
  std::vector<FrfChannel> out;
  for (const auto& n : names) {
    std::string unit;
    for (const auto& s : plant->signals()) {
      if (s.name == n) unit = s.unit;
    }
    for (const auto& s : plant->commands()) {
      if (s.name == n) unit = s.unit;
    }
    out.push_back({n, unit});
  }
  return out;
}

IdentifyResult run_identify(const IdentifyOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  IdentifyResult result;
  RigConfig config = load_rig_config(o.config_path, o.case_name);
  if (!config.more_channels.empty()) {
    MimoIdentifyResult m = run_mimo_identify(o, stop, out);
    result.aborted = m.aborted;
    result.abort_reason = m.abort_reason;
    result.matrix = std::move(m.matrix);
    result.run = std::move(m.run);
    if (!o.plot_path.empty()) out << "  --plot: not drawn for a matrix FRF (no plot of one yet)\n";
    return result;
  }
  result.plan = plan_identification(std::move(config), o.settings);
  const IdentifyPlan& plan = result.plan;
  const Excitation excitation = make_excitation(plan.excitation);
  describe_plan(plan, out);

  RunOptions ro;
  ro.config_path = o.config_path;
  ro.case_name = o.case_name;
  ro.fast = o.fast;
  ro.realtime = o.realtime;
  ro.log_path = o.log_path;
  ro.csv_path = o.csv_path.empty() ? identify_default_csv_path(o.out_path) : o.csv_path;
  ro.profile_override = [&] { return excitation_profile(plan, excitation); };
  result.run = run_rig(plan.config, ro, stop, out);
  if (result.run.loop.final_state == RigState::kFaulted || stop.load()) {
    result.aborted = true;
    result.abort_reason = stop.load() ? "stop requested" : result.run.end_reason;
    out << "  identification aborted: " << result.abort_reason << "; the valve is at null, no FRF written\n";
    return result;
  }

  const std::string setpoint = setpoint_name_for(plan.config.rig);
  const auto demand = FrfChannel{setpoint, frf_channels(plan.config, {plan.config.controller.feedback})[0].unit};
  const auto command = frf_channels(plan.config, {plan.config.controller.output})[0];
  const auto responses = frf_channels(plan.config, plan.responses);
  RunFileOptions columns;
  columns.required = {setpoint, command.name};
  columns.required.insert(columns.required.end(), plan.responses.begin(), plan.responses.end());
  const RunFile run = read_run_file(ro.csv_path, columns);
  result.frf = analyse_identification(run, plan, excitation, demand, command, responses);
  FrfData& f = result.frf;
  f.rig = std::string(to_string(plan.config.rig));
  f.config = o.config_path;
  f.run_log = result.run.log_path;
  f.controller_type = std::string(to_string(plan.config.controller.type));
  f.controller_gains = controller_gains(plan.config.controller);
  if (is_simulated(plan.config.driver)) {
    f.model = linearised_plant_frf(plan.config, f.operating_point.response_mean, plan.responses, f.frequency_hz);
  }
  describe_frf(f, out);
  write_frf_file(f, o.out_path);
  out << "  frf: " << o.out_path << "\n";
  if (!o.plot_path.empty()) {
    plot_frf(o.out_path, o.plot_path);
    out << "  plot: " << o.plot_path << "\n";
  }
  return result;
}

void plot_frf(const std::string& frf_path, const std::string& png_path, const std::string& tune_json) {
  const char* dir = std::getenv("RIGCTL_PLOTS_DIR");
  const std::string script = std::string(dir != nullptr ? dir : RIGCTL_PLOTS_DIR) + "/plot_frf.py";
  std::string cmd = "/usr/bin/python3 '" + script + "' '" + frf_path + "' --out '" + png_path + "'";
  if (!tune_json.empty()) cmd += " --tune '" + tune_json + "'";
  const int status = std::system(cmd.c_str());
  if (status != 0) {
    throw std::runtime_error("plotting failed (" + cmd + "); matplotlib comes with tools/scripts/setup.sh --plots");
  }
}

}  // namespace rigctl
