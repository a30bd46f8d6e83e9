#include "tools/tune/tune_command.hpp"

#include <filesystem>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/identify/identify_command.hpp"
#include "tools/tune/plant_fit.hpp"
#include "tools/tune/relay_experiment.hpp"
#include "tools/tune/tune_report.hpp"
#include "tools/tune/tuned_config.hpp"

namespace rigctl {

namespace {

// The gains the FRF was measured with, in the loop's form.
LoopGains gains_of_frf(const FrfData& frf, LoopGains base) {
  const auto& g = frf.controller_gains;
  auto get = [&](const char* k, double fallback) {
    const auto it = g.find(k);
    return it == g.end() ? fallback : it->second;
  };
  base.kp = get("kp", 0.0);
  base.ki = get("ki", 0.0);
  base.ke = get("ke", 0.0);
  base.kv = get("kv", 0.0);
  base.kp_pressure = get("kp_v_per_bar", 0.0) / 1e5;
  base.transient_pressure = get("transient_pressure", base.transient_pressure ? 1.0 : 0.0) != 0.0;
  base.transient_tau_s = get("transient_tau_s", base.transient_tau_s);
  base.velocity_filter_tau_s = get("velocity_filter_tau_s", base.velocity_filter_tau_s);
  return base;
}

void check_same_rig(const RigConfig& c, const FrfData& frf, const std::string& path) {
  if (frf.rig != to_string(c.rig)) {
    throw std::runtime_error(path + ": measured on a " + frf.rig + " rig, the config is a " + std::string(to_string(c.rig)));
  }
  if (frf.controller_type != to_string(c.controller.type)) {
    throw std::runtime_error(path + ": measured with a " + frf.controller_type + " controller, the config has " +
                             std::string(to_string(c.controller.type)));
  }
}

// The FRF's part: the present loop's margins, the design (FRF method), the
// margins of the gains on the measured plant, the fitted model and the
// predicted step. Returns the fitted model.
PlantModel design_on_frf(const FrfData& frf, const RigConfig& config, const LoopGains& base, const TuneOptions& o,
                         TuneResult& result, std::ostream& out) {
  const PlantResponse plant = PlantResponse::from_frf(frf);
  const PlantGrid grid(plant);
  result.present_margins = margins_of(grid, gains_of_frf(frf, base));
  print_margins("measured loop (the gains of the identification)", *result.present_margins, out);
  print_margins("measured closed loop as T / (1 - T)", closed_loop_margins(frf), out);
  if (o.method == TuneMethod::kFrf) {
    DesignTarget target = o.target;
    if (config.profile.type == ProfileKind::kRampSteps && config.profile.filter_tau_s == 0.0) {
      target.max_demand_gain = base.output_limit / std::abs(standard_step(config).step);
    }
    const LoopDesign d = design_loop(grid, base, target);
    result.gains = d.gains;
    result.note = d.note;
  }
  result.margins = margins_of(grid, result.gains);
  PlantModel model = fit_plant(plant, config.loop.period_s);
  if (o.method == TuneMethod::kFrf) {
    FeedforwardDesign ff;
    if (o.feedforward) {
      ff = design_feedforward(plant, result.margins->crossover_hz, config);
    } else {
      ff.reason_for_none = "--no-feedforward";
    }
    result.gains.kff = ff.kff;
    result.feedforward = ff;
  }
  if (config.profile.type == ProfileKind::kRampSteps) {
    result.step = predict_step(model, result.gains, config, frf.operating_point.command_mean);
  }
  return model;
}

}  // namespace

TuneResult run_tune(const TuneOptions& o, const std::atomic<bool>& stop, std::ostream& out) {
  const RigConfig config = load_rig_config(o.config_path, o.case_name);
  const LoopGains base = LoopGains::from_config(config);
  TuneResult result;
  if (!o.evaluate_path.empty()) {
    const StepMetrics m = measured_step(config, o.evaluate_path);
    out << "rigctl tune --evaluate: " << o.evaluate_path << ": overshoot " << 100.0 * m.overshoot << " %, settling (2 %) "
        << m.settling_s << " s, IAE " << m.iae << "\n";
    result.gains = base;
    return result;
  }
  std::optional<FrfData> frf;
  std::optional<RelayResult> relay;
  std::optional<PlantModel> model;
  if (!o.frf_path.empty()) {
    frf = read_frf_file(o.frf_path);
    check_same_rig(config, *frf, o.frf_path);
  }
  if (o.method == TuneMethod::kRelay) {
    relay = run_relay_experiment(config, o, 0.0, stop, out);
    if (relay->aborted) throw std::runtime_error("relay experiment aborted: " + relay->abort_reason + " (the valve is at null)");
    result.gains = relay->gains;
  } else if (!frf) {
    throw std::runtime_error("--frf FRF.json is needed (rigctl identify writes it), or --method relay");
  }
  if (frf) model = design_on_frf(*frf, config, base, o, result, out);
  const TuneReportInput report{std::string(to_string(config.rig)), &o, &result, frf ? &*frf : nullptr,
                               relay ? &*relay : nullptr, model ? &*model : nullptr};
  print_tune(report, out);
  if (!o.out_path.empty()) {
    write_tuned_config(o.config_path, o.out_path, result.gains.config_values());
    out << "  tuned config: " << o.out_path << "\n";
  }
  std::string json = o.json_path;
  if (json.empty() && !o.plot_path.empty()) json = (std::filesystem::temp_directory_path() / "rigctl-tune.json").string();
  if (!json.empty()) write_tune_json(report, json);
  if (!o.json_path.empty()) out << "  design: " << o.json_path << "\n";
  if (!o.plot_path.empty()) {
    if (!frf) throw std::runtime_error("--plot needs --frf (the plot shows the measured plant and the tuned loop)");
    plot_frf(o.frf_path, o.plot_path, json);
    out << "  plot: " << o.plot_path << "\n";
  }
  return result;
}

}  // namespace rigctl
