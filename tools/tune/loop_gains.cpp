#include "tools/tune/loop_gains.hpp"

#include <stdexcept>

namespace rigctl {

LoopGains LoopGains::from_config(const RigConfig& c) {
  LoopGains g;
  g.kind = c.controller.type;
  g.period_s = c.loop.period_s;
  switch (g.kind) {
    case ControllerKind::kPi:
      g.kp = c.controller.pi.kp;
      g.ki = c.controller.pi.ki;
      g.kff = c.controller.pi.velocity_feedforward;
      g.output_limit = c.controller.pi.output_limit;
      return g;
    case ControllerKind::kPvp: {
      const PvpConfig& p = c.controller.pvp;
      g.ke = p.ke;
      g.kv = p.kv;
      g.kp_pressure = p.kp;
      g.transient_pressure = p.transient_pressure;
      g.transient_tau_s = p.tau_f;
      g.velocity_filter_tau_s = p.velocity_filter_tau;
      g.output_limit = p.output_limit;
      return g;
    }
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: break;
  }
  throw std::invalid_argument("tuning needs a position controller (pi or pvp), not " + std::string(to_string(g.kind)));
}

std::map<std::string, double> LoopGains::config_values() const {
  if (kind == ControllerKind::kPi) return {{"kp", kp}, {"ki", ki}, {"velocity_feedforward", kff}};
  return {{"ke", ke}, {"kv", kv}, {"kp_v_per_bar", kp_pressure * 1e5}};
}

void LoopGains::apply_to(ControllerConfig& c) const {
  if (kind == ControllerKind::kPi) {
    c.pi.kp = kp;
    c.pi.ki = ki;
    c.pi.velocity_feedforward = kff;
  } else {
    c.pvp.ke = ke;
    c.pvp.kv = kv;
    c.pvp.kp = kp_pressure;
  }
}

}  // namespace rigctl
