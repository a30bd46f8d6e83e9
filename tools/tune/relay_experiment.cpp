#include "tools/tune/relay_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "tools/identify/amplitude_clamp.hpp"
#include "tools/identify/excitation_profile.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/run/run_command.hpp"
#include "tools/runfile/run_file.hpp"
#include "tools/tune/relay_controller.hpp"

namespace rigctl {

namespace {

constexpr double kSettleS = 3.0;          // hold at the operating point before relaying
constexpr double kDiscardShare = 1.0 / 3; // the first third of the relay time: the cycle building up

// 3 x the feedback sensor's noise (and at least one ADC step): noise alone
// must not switch the relay.
double default_hysteresis(const RigConfig& c) {
  const auto it = c.sensors.find(c.controller.feedback);
  if (it == c.sensors.end()) return 0.0;
  const SensorSpec& s = it->second;
  const double lsb = s.bits > 0 ? (s.range_max - s.range_min) / std::pow(2.0, s.bits) : 0.0;
  return 3.0 * std::max(s.noise_sd, lsb);
}

double proportional_gain(const RigConfig& c) {
  return c.controller.type == ControllerKind::kPi ? c.controller.pi.kp : c.controller.pvp.ke;
}

struct Cycle {
  double period = 0.0, amplitude = 0.0, relay = 0.0, hold = 0.0;
  int cycles = 0;
};

// Period between same-direction switchings and the response's half
// peak-to-peak over whole cycles, in the analysed window [from, to).
Cycle analyse_cycle(const std::vector<double>& t, const std::vector<double>& u, const std::vector<double>& y,
                    std::size_t from, std::size_t to) {
  const auto [lo, hi] = std::minmax_element(u.begin() + static_cast<std::ptrdiff_t>(from), u.begin() + static_cast<std::ptrdiff_t>(to));
  Cycle c;
  c.hold = 0.5 * (*lo + *hi);
  c.relay = 0.5 * (*hi - *lo);
  std::vector<std::size_t> ups;
  for (std::size_t i = from + 1; i < to; ++i) {
    if (u[i - 1] < c.hold && u[i] > c.hold) ups.push_back(i);
  }
  if (ups.size() < 3) return c;
  c.cycles = static_cast<int>(ups.size() - 1);
  c.period = (t[ups.back()] - t[ups.front()]) / c.cycles;
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < ups.size(); ++k) {
    const auto [ylo, yhi] = std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(ups[k]), y.begin() + static_cast<std::ptrdiff_t>(ups[k + 1]));
    sum += 0.5 * (*yhi - *ylo);
  }
  c.amplitude = sum / c.cycles;
  return c;
}

}  // namespace

LoopGains ziegler_nichols(LoopGains g, double ku, double tu) {
  if (g.kind == ControllerKind::kPi) {
    g.kp = 0.45 * ku;
    g.ki = g.kp / (tu / 1.2);
    g.kff = 0.0;  // the rules are for the feedback gains; a feedforward of another design does not carry over
  } else {
    g.ke = 0.6 * ku;
    g.kv = g.ke * tu / 8.0;
    g.kp_pressure = 0.0;
  }
  return g;
}

namespace {

RelaySettings relay_settings(const RigConfig& c, const RelayOptions& ro, double stabiliser_gain, double op) {
  const LoopGains base = LoopGains::from_config(c);
  RelaySettings s;
  s.stabiliser_gain = stabiliser_gain > 0.0 ? stabiliser_gain : proportional_gain(c);
  s.output_limit = base.output_limit;
  s.amplitude = ro.amplitude > 0.0 ? ro.amplitude : 0.1 * base.output_limit;  // a tenth of the valve's range
  s.hysteresis = ro.hysteresis > 0.0 ? ro.hysteresis : default_hysteresis(c);
  s.amplitude_clamp = amplitude_clamp(c, op, c.identify.band_min_hz).limit;
  s.hold_ticks = std::llround((lead_in_to(c, op).duration() + kSettleS) / c.loop.period_s);
  s.learn_ticks = std::llround(1.0 / c.loop.period_s);
  return s;
}

// The limit cycle in the run file: the relay starts hold_ticks after the
// first driven tick; its first third is left out.
Cycle cycle_in_run(const std::string& csv, const RigConfig& c, const RelaySettings& s, double duration_s) {
  const RunFile f = read_run_file(csv, RunFileOptions{{c.controller.output, c.controller.feedback}, {}, false, 10});
  const auto& u = f.col(c.controller.output);
  std::size_t first_driven = 0;
  while (first_driven < u.size() && u[first_driven] == 0.0) ++first_driven;
  const auto relay_start = first_driven + static_cast<std::size_t>(s.hold_ticks);
  const auto relay_ticks = static_cast<std::size_t>(duration_s / c.loop.period_s);
  const std::size_t from = relay_start + static_cast<std::size_t>(kDiscardShare * static_cast<double>(relay_ticks));
  const std::size_t to = std::min(u.size(), relay_start + relay_ticks);
  const Cycle cycle = from < to ? analyse_cycle(f.t, u, f.col(c.controller.feedback), from, to) : Cycle{};
  if (cycle.cycles < 2 || !(cycle.amplitude > s.hysteresis)) {
    throw std::runtime_error("the relay found no limit cycle (" + std::to_string(cycle.cycles) + " cycles, amplitude " +
                             std::to_string(cycle.amplitude) + "): lengthen --relay-duration or raise --relay-amplitude");
  }
  return cycle;
}

}  // namespace

RelayResult run_relay_experiment(const RigConfig& config, const TuneOptions& o, double stabiliser_gain,
                                 const std::atomic<bool>& stop, std::ostream& out) {
  const RelayOptions& ro = o.relay;
  const double op = default_operating_point(config);
  const RelaySettings s = relay_settings(config, ro, stabiliser_gain, op);
  out << "rigctl tune --method relay: relay +-" << s.amplitude << " about the hold command, hysteresis " << s.hysteresis
      << ", amplitude clamp " << s.amplitude_clamp << ", " << ro.duration_s << " s about " << config.controller.feedback
      << " = " << op << "\n";
  RunOptions run;
  run.config_path = o.config_path;
  run.fast = ro.fast;
  run.realtime = ro.realtime;
  run.log_path = ro.log_path;
  run.csv_path = (ro.log_path.empty() ? std::filesystem::temp_directory_path().string() + "/rigctl-relay" : ro.log_path) + ".csv";
  run.profile_override = [&] {
    return std::make_unique<ExcitationProfile>(lead_in_to(config, op), kSettleS, std::vector<double>{}, config.loop.period_s,
                                               ro.duration_s);
  };
  run.controller_override = [&](const ChannelLayout& layout) {
    RelaySettings placed = s;
    placed.feedback_input = layout.input_index(config.controller.feedback);
    placed.output_index = layout.output_index(config.controller.output);
    return std::make_unique<RelayController>(placed);
  };
  RelayResult r;
  const RunReport report = run_rig(config, run, stop, out);
  r.log_path = report.log_path;
  r.hysteresis = s.hysteresis;
  if (report.loop.final_state == RigState::kFaulted || stop.load()) {
    r.aborted = true;
    r.abort_reason = stop.load() ? "stop requested" : report.end_reason;
    return r;
  }
  const Cycle c = cycle_in_run(run.csv_path, config, s, ro.duration_s);
  r.ultimate_period_s = c.period;
  r.oscillation_amplitude = c.amplitude;
  r.relay_amplitude = c.relay;
  r.hold_command = c.hold;
  r.cycles = c.cycles;
  r.ultimate_gain = 4.0 * c.relay / (std::numbers::pi * std::sqrt(c.amplitude * c.amplitude - s.hysteresis * s.hysteresis));
  r.gains = ziegler_nichols(LoopGains::from_config(config), r.ultimate_gain, r.ultimate_period_s);
  out << "  limit cycle: Tu " << r.ultimate_period_s << " s, amplitude " << r.oscillation_amplitude << " for relay +-"
      << r.relay_amplitude << " (" << r.cycles << " cycles): Ku " << r.ultimate_gain << "\n";
  return r;
}

}  // namespace rigctl
