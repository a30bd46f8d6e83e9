// Quarter-car part of the hidden-effect generator (seed 000 rig).
#include <stdexcept>

#include "tools/hidden_effects_rigs.hpp"

namespace rigctl {

namespace {

void make_clean(RigConfig& c) {
  c.quarter_car.bearing_friction.enabled = false;
  for (auto& [name, s] : c.sensors) s.offset = 0.0;
}

AppliedEffect apply(RigConfig& c, const std::string& cause, double level) {
  AppliedEffect a;
  a.cause = cause;
  a.level = level;
  if (cause == "bearing_friction") {
    // Karnopp stick/slip with normal-force dependent Coulomb level (plant/bearing_friction.*),
    // fitted by the diagnosis with a smooth Stribeck law: not the same formula.
    auto& b = c.quarter_car.bearing_friction;
    b.enabled = true;
    b.coulomb_base *= level;
    b.stiction_excess *= level;
    b.viscous *= level;
    a.truth = {{"Fc0", b.coulomb_base}, {"dFs", b.stiction_excess}, {"D", b.viscous}};
    a.description = "body-bearing Karnopp stick/slip friction, nominal levels x " + std::to_string(level);
    return a;
  }
  if (cause == "sensor_offset") {
    const double b = 2e-3 * level;  // 2 mm on x_b, strong
    c.sensors["x_b"].offset = b;
    a.truth = {{"b_b", b}};
    a.description = "offset on the x_b transducer";
    return a;
  }
  throw std::invalid_argument("quarter_car: no hidden effect '" + cause + "' (yet)");
}

}  // namespace

const RigEffectGenerator& quarter_car_effect_generator() {
  static const RigEffectGenerator g{
      "quarter_car",
      {"bearing_friction", "actuator_seal_friction", "cross_port_leakage", "valve_deadband", "entrained_air",
       "sensor_delay", "sensor_offset", "tyre_liftoff", "damper_asymmetry"},
      "",
      make_clean,
      apply,
  };
  return g;
}

}  // namespace rigctl
