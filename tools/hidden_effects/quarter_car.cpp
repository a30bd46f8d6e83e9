// Quarter-car part of the hidden-effect generator (seed 000 rig). Strong
// levels are chosen so that each effect changes the recorded run by clearly
// more than the sensor noise; weak ones (0.35 of strong) sit near what the
// diagnosis can still tell apart. The plant makes each effect with its own
// formula (QuarterCarHiddenEffects, plant/quarter_car/quarter_car_params.hpp), not with
// the diagnosis candidate's.
#include <filesystem>
#include <stdexcept>

#include "tools/hidden_effects/rigs.hpp"

namespace rigctl {

namespace {

void make_clean(RigConfig& c) {
  c.quarter_car.bearing_friction.enabled = false;
  c.quarter_car.hidden = QuarterCarHiddenEffects{};
}

AppliedEffect apply(RigConfig& c, const std::string& cause, double level) {
  AppliedEffect a;
  a.cause = cause;
  a.level = level;
  auto& h = c.quarter_car.hidden;
  if (cause == "bearing_friction") {
    // Karnopp stick/slip with a normal-force dependent Coulomb level
    // (plant/bearing_friction.*); the diagnosis fits a smooth Stribeck law.
    auto& b = c.quarter_car.bearing_friction;
    b.enabled = true;
    b.coulomb_base *= level;
    b.stiction_excess *= level;
    b.viscous *= level;
    b.normal_coefficient *= level;
    a.truth = {{"Fc", b.coulomb_base}, {"dFs", b.stiction_excess}, {"D", b.viscous}};
    a.description = "body-bearing Karnopp stick/slip friction at the nominal levels x level";
  } else if (cause == "actuator_seal_friction") {
    // 150 N preload + 5e-6 N/Pa x (p1 + p2) (about 100 N at the ~200 bar sum):
    // about 1 % of the ~20 kN rod force of a step (A1 p1).
    h.seal_preload = 150.0 * level;
    h.seal_pressure_coefficient = 5e-6 * level;
    h.seal_viscous = 300.0 * level;
    a.truth = {{"F_pr", h.seal_preload}, {"f_c", h.seal_pressure_coefficient}, {"viscous", h.seal_viscous}};
    a.description = "rod seal friction, Simscape cylinder-friction form (Stribeck peak 1.3 x Coulomb at 20 mm/s)";
  } else if (cause == "cross_port_leakage") {
    // A worn piston seal: turbulent leak of 2 x the nominal laminar leak at 50 bar.
    const double nominal_at_50bar = 50e5 / c.quarter_car.leakage_resistance;
    h.worn_seal_orifice = 2.0 * level * nominal_at_50bar / std::sqrt(50e5);
    a.truth = {{"K_orifice", h.worn_seal_orifice}, {"extra_leak_at_50bar_m3_s", 2.0 * level * nominal_at_50bar}};
    a.description = "turbulent cross-port leak through a worn piston seal, K sign(dp) sqrt|dp|";
  } else if (cause == "valve_deadband") {
    h.valve_overlap = 0.05 * level;  // 5 % of rated spool travel: a lapped, worn-in spool
    a.truth = {{"overlap", h.valve_overlap}};
    a.description = "sharp spool overlap (no metering inside +-overlap)";
  } else if (cause == "entrained_air") {
    // alpha 0.15 at atmosphere: -27 % bulk modulus at the cap side's ~75 bar.
    h.air_fraction = 0.15 * level;
    QuarterCarParams p = c.quarter_car;
    const double pabs = 101325.0 + 75e5, pa = 101325.0, e = p.bulk_modulus, al = h.air_fraction;
    const double e75 = e * (1.0 + al * pa / pabs) / (1.0 + al * pa * e / (pabs * pabs));
    a.truth = {{"air_fraction", h.air_fraction}, {"beta_at_75bar", e75}, {"beta_ratio_at_75bar", e75 / e}};
    a.description = "free air in the oil: pressure-dependent effective bulk modulus (isothermal mixture law)";
  } else if (cause == "sensor_delay") {
    // 6 ms strong (2.4 periods; an LVDT demodulator filter): not a whole number of samples.
    const double tau = 0.006 * level;
    c.sensors["x_w"].delay_s = tau;
    c.sensors["x_b"].delay_s = tau;
    a.truth = {{"tau", tau}};
    a.description = "x_w and x_b transducers late by tau (cubic interpolation of the true signal's history)";
  } else if (cause == "sensor_offset") {
    const double b = 2e-3 * level;  // 2 mm on the body LVDT: a zero not reset after a fixture change
    c.sensors["x_b"].offset = b;
    a.truth = {{"b_b", b}};
    a.description = "offset on the x_b transducer";
  } else if (cause == "tyre_liftoff") {
    // Lift-off is physics, not a switch: a real tyre never pulls, and the
    // clean excitation never unloads it (lowest load ~0.3 kN). The effect is
    // a run that does: the demand gets a wheel-hop burst, the tyre cannot
    // pull (weak: part of the pull is lost, a tyre glued by its tread).
    // The `diagnosis` case's table with a wheel-hop burst added (beside it).
    switch (c.profile.type) {
      case ProfileKind::kCsv:
        c.profile.csv_file =
            (std::filesystem::path(c.profile.csv_file).parent_path() / "quarter_car_liftoff_demand.csv").string();
        break;
      case ProfileKind::kRampSteps:  // no table to swap: the tyre alone
      case ProfileKind::kSine:
      case ProfileKind::kHold:
        break;
    }
    h.tyre_pull_loss = std::min(1.0, level);
    a.truth = {{"pull_loss", h.tyre_pull_loss}};
    a.description = "wheel-hop burst in the demand and a tyre that cannot pull (weak: part of the pull lost)";
  } else if (cause == "damper_asymmetry") {
    // Rebound 1.6 x, compression 0.4 x the nominal 260 N s/m (strong): a
    // typical road damper's rebound/compression ratio of 3-4.
    h.damper_rebound_factor = 1.0 + 0.6 * level;
    h.damper_compression_factor = 1.0 - 0.6 * level;
    const double bd = c.quarter_car.damper_damping;
    // The diagnosis fits bd + dc tanh(v_rel / 0.01): at speed, dc = (c_comp - c_reb) / 2.
    a.truth = {{"c_rebound", bd * h.damper_rebound_factor},
               {"c_compression", bd * h.damper_compression_factor},
               {"dc", 0.5 * bd * (h.damper_compression_factor - h.damper_rebound_factor)}};
    a.description = "piecewise-linear damper: rebound and compression coefficients differ";
  } else {
    throw std::invalid_argument("quarter_car has no effect '" + cause +
                                "' (bearing_friction, actuator_seal_friction, cross_port_leakage, valve_deadband, "
                                "entrained_air, sensor_delay, sensor_offset, tyre_liftoff, damper_asymmetry)");
  }
  return a;
}

}  // namespace

const RigEffectGenerator& quarter_car_effect_generator() {
  static const RigEffectGenerator g{
      RigKind::kQuarterCar,
      {"bearing_friction", "actuator_seal_friction", "cross_port_leakage", "valve_deadband", "entrained_air",
       "sensor_delay", "sensor_offset", "tyre_liftoff", "damper_asymmetry"},
      "diagnosis",
      make_clean,
      apply,
  };
  return g;
}

}  // namespace rigctl
