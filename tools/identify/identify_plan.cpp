#include "tools/identify/identify_plan.hpp"

#include <algorithm>

#include <cmath>

#include "config/config_reader.hpp"

namespace rigctl {

namespace {

void use_stabiliser(ControllerConfig& c, double gain) {
  switch (c.type) {
    case ControllerKind::kPi:
      c.pi.kp = gain;
      c.pi.ki = 0.0;
      return;
    case ControllerKind::kPvp:
      c.pvp.ke = gain;
      c.pvp.kv = 0.0;
      c.pvp.kp = 0.0;
      return;
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: return;
  }
}

// During identification a trip of any detector ends the excitation at once:
// a limit reached means the excitation is unsafe, and a held or ramped rig
// would leave the record meaningless anyway.
void every_trip_interlocks(SafetyConfig& s) {
  s.limits_action = LimitAction::kInterlock;
  for (auto& d : s.detectors) d.action = LimitAction::kInterlock;
}

}  // namespace

double default_operating_point(const RigConfig& c) {
  const auto& s = c.safety;
  if (std::isfinite(s.setpoint_min) && std::isfinite(s.setpoint_max)) return 0.5 * (s.setpoint_min + s.setpoint_max);
  return c.profile.ramp_target;
}

std::map<std::string, double> controller_gains(const ControllerConfig& c) {
  switch (c.type) {
    case ControllerKind::kPi: return {{"kp", c.pi.kp}, {"ki", c.pi.ki}, {"output_limit", c.pi.output_limit}};
    case ControllerKind::kPvp:
      return {{"ke", c.pvp.ke},
              {"kv", c.pvp.kv},
              {"kp_v_per_bar", c.pvp.kp * 1e5},
              {"transient_pressure", c.pvp.transient_pressure ? 1.0 : 0.0},
              {"transient_tau_s", c.pvp.tau_f},
              {"velocity_filter_tau_s", c.pvp.velocity_filter_tau},
              {"output_limit", c.pvp.output_limit}};
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: break;
  }
  return {};
}

IdentifyPlan plan_identification(RigConfig config, const IdentifySettings& s) {
  const ControllerKind kind = config.controller.type;
  if (kind != ControllerKind::kPi && kind != ControllerKind::kPvp) {
    throw ConfigError(config.file + ": controller.type: identification needs a position loop (pi or pvp), not " +
                      std::string(to_string(kind)));
  }
  if (s.stabiliser_gain) use_stabiliser(config.controller, *s.stabiliser_gain);
  // The feedback loop is what is measured: a demand feedforward would add a
  // path around it, and the closed loop would no longer be L / (1 + L)
  // (the margins read from it as T / (1 - T) would be wrong).
  config.controller.pi.velocity_feedforward = 0.0;
  every_trip_interlocks(config.safety);
  const IdentifyConfig& ic = config.identify;

  IdentifyPlan plan;
  plan.operating_point = s.operating_point.value_or(ic.operating_point.value_or(default_operating_point(config)));
  ExcitationSpec& e = plan.excitation;
  e.kind = s.excitation.value_or(ic.excitation);
  e.band_min_hz = s.band_min_hz.value_or(ic.band_min_hz);
  e.band_max_hz = s.band_max_hz.value_or(ic.band_max_hz);
  e.duration_s = s.duration_s.value_or(ic.duration_s);
  e.resolution_hz = s.resolution_hz.value_or(ic.resolution_hz);
  e.period_s = config.loop.period_s;
  e.seed = config.seed;
  plan.clamp = amplitude_clamp(config, plan.operating_point, e.band_min_hz);
  const std::optional<double> requested = s.amplitude ? s.amplitude : ic.amplitude;
  plan.amplitude_requested = requested.value_or(0.0);
  e.amplitude = requested ? std::min(*requested, plan.clamp.limit) : plan.clamp.limit;
  plan.settle_s = s.settle_s.value_or(ic.settle_s);
  plan.responses = {config.controller.feedback};
  if (kind == ControllerKind::kPvp) plan.responses.push_back(config.controller.pressure);
  for (const auto& extra : s.extra_responses) {
    if (std::find(plan.responses.begin(), plan.responses.end(), extra) == plan.responses.end()) plan.responses.push_back(extra);
  }
  plan.config = std::move(config);
  return plan;
}

}  // namespace rigctl
