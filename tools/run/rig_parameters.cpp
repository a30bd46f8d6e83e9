#include "tools/run/rig_parameters.hpp"

#include <cmath>
#include <string>

namespace rigctl {

namespace {

class Parameters {
 public:
  // Infinite values are "no limit" in the config: left out.
  void add(const std::string& name, double value) {
    if (std::isfinite(value)) list.push_back({name, value});
  }
  std::vector<foxglove::Parameter> list;
};

void add_controller(const RigConfig& c, Parameters& p) {
  switch (c.controller.type) {
    case ControllerKind::kPi:
      p.add("controller.kp", c.controller.pi.kp);
      p.add("controller.ki", c.controller.pi.ki);
      p.add("controller.output_limit", c.controller.pi.output_limit);
      return;
    case ControllerKind::kPvp:
      p.add("controller.ke", c.controller.pvp.ke);
      p.add("controller.kv", c.controller.pvp.kv);
      p.add("controller.kp", c.controller.pvp.kp);
      p.add("controller.tau_f", c.controller.pvp.tau_f);
      p.add("controller.velocity_filter_tau", c.controller.pvp.velocity_filter_tau);
      p.add("controller.output_limit", c.controller.pvp.output_limit);
      return;
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kLqr:
      p.add("controller.force_limit_n", c.controller.suspension.force_limit);
      return;
    case ControllerKind::kSkyhook:
      p.add("controller.force_limit_n", c.controller.suspension.force_limit);
      p.add("controller.skyhook.c_sky", c.controller.suspension.skyhook_c_sky);
      return;
  }
}

}  // namespace

std::vector<foxglove::Parameter> rig_parameters(const RigConfig& c) {
  Parameters p;
  p.add("loop.period_s", c.loop.period_s);
  add_controller(c, p);
  for (const auto& l : c.limits) {
    p.add("limits." + l.channel + ".min", l.min);
    p.add("limits." + l.channel + ".max", l.max);
  }
  p.add("safety.hold_deceleration", c.safety.hold_deceleration);
  p.add("safety.setpoint_rate", c.safety.setpoint_rate);
  p.add("safety.setpoint_range.min", c.safety.setpoint_min);
  p.add("safety.setpoint_range.max", c.safety.setpoint_max);
  p.add("safety.stop_timeout_s", c.safety.stop_timeout_s);
  for (const auto& d : c.safety.detectors) {
    const std::string key = "safety.detectors." + d.name + ".";
    p.add(key + "min", d.min);
    p.add(key + "max", d.max);
    if (d.duration_s > 0.0) p.add(key + "duration_s", d.duration_s);
  }
  return p.list;
}

}  // namespace rigctl
