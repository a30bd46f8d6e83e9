// Quarter-car part of the hidden-effect generator (seed 000 rig). Strong
// levels are chosen so that each effect changes the recorded run by clearly
// more than the sensor noise; weak ones (0.35 of strong) sit near what the
// diagnosis can still tell apart. The plant makes each effect with its own
// formula (QuarterCarHiddenEffects, plant/quarter_car/quarter_car_params.hpp), not with
// the diagnosis candidate's, in two physical forms (form 0 / form 1):
//   bearing_friction        Karnopp stick/slip        / LuGre bristles
//   actuator_seal_friction  Simscape cylinder law     / exponential Stribeck on a steep step
//   cross_port_leakage      turbulent worn-seal orifice / laminar plus turbulent
//   valve_deadband          sharp lands               / rounded metering edges
//   entrained_air           isothermal bubbles        / adiabatic bubbles
//   sensor_delay            cubic delay line          / 2nd-order Butterworth conditioning filter
//   sensor_offset           on x_b                    / on x_w
//   tyre_liftoff            no pull, damper kept      / no pull, no damper off contact
//   damper_asymmetry        piecewise linear          / progressive rebound valve
#include <filesystem>
#include <stdexcept>

#include "drivers/sim/conditioning_filter.hpp"
#include "plant/quarter_car/hidden_effect_laws.hpp"
#include "tools/hidden_effects/perturbation.hpp"
#include "tools/hidden_effects/rigs.hpp"

namespace rigctl {

namespace {

void make_clean(RigConfig& c) {
  c.quarter_car.bearing_friction.enabled = false;
  c.quarter_car.hidden = QuarterCarHiddenEffects{};
}

AppliedEffect apply(RigConfig& c, const std::string& cause, double level, int form) {
  AppliedEffect a;
  a.cause = cause;
  a.level = level;
  auto& h = c.quarter_car.hidden;
  if (cause == "bearing_friction") {
    // Karnopp stick/slip with a normal-force dependent Coulomb level
    // (plant/bearing_friction.*), or LuGre bristles with the same levels;
    // the diagnosis fits a smooth Stribeck law.
    auto& b = c.quarter_car.bearing_friction;
    b.enabled = form == 0;
    h.bearing_lugre = form == 1;
    a.form = form == 0 ? "karnopp" : "lugre";
    b.coulomb_base *= level;
    b.stiction_excess *= level;
    b.viscous *= level;
    b.normal_coefficient *= level;
    a.truth = {{"Fc", b.coulomb_base}, {"dFs", b.stiction_excess}, {"D", b.viscous}};
    a.description = form == 0 ? "body-bearing Karnopp stick/slip friction at the nominal levels x level"
                              : "body-bearing LuGre bristle friction at the nominal levels x level";
  } else if (cause == "actuator_seal_friction") {
    // 150 N preload + 5e-6 N/Pa x (p1 + p2) (about 100 N at the ~200 bar sum):
    // about 1 % of the ~20 kN rod force of a step (A1 p1).
    h.seal_preload = 150.0 * level;
    h.seal_pressure_coefficient = 5e-6 * level;
    h.seal_viscous = 300.0 * level;
    h.seal_form = form;
    a.form = form == 0 ? "simscape" : "exponential_stribeck";
    a.truth = {{"F_pr", h.seal_preload}, {"f_c", h.seal_pressure_coefficient}, {"viscous", h.seal_viscous}};
    a.description = form == 0 ? "rod seal friction, Simscape cylinder-friction form (Stribeck peak 1.3 x Coulomb at 20 mm/s)"
                              : "rod seal friction, exponential Stribeck law on a 1 mm/s Coulomb step, plus viscous";
  } else if (cause == "cross_port_leakage") {
    // A worn piston seal: turbulent leak of 2 x the nominal laminar leak at 50 bar.
    // Form 1 splits the same extra flow at 50 bar half laminar, half turbulent.
    const double nominal_at_50bar = 50e5 / c.quarter_car.leakage_resistance;
    const double turbulent_share = form == 0 ? 1.0 : 0.5;
    h.worn_seal_orifice = turbulent_share * 2.0 * level * nominal_at_50bar / std::sqrt(50e5);
    h.extra_laminar_leak = (1.0 - turbulent_share) * 2.0 * level * nominal_at_50bar / 50e5;
    a.form = form == 0 ? "turbulent" : "laminar_and_turbulent";
    a.truth = {{"K_orifice", h.worn_seal_orifice}, {"extra_leak_at_50bar_m3_s", 2.0 * level * nominal_at_50bar}};
    a.description = form == 0 ? "turbulent cross-port leak through a worn piston seal, K sign(dp) sqrt|dp|"
                              : "cross-port leak through a worn piston seal, half laminar, half turbulent at 50 bar";
  } else if (cause == "valve_deadband") {
    h.valve_overlap = 0.05 * level;  // 5 % of rated spool travel: a lapped, worn-in spool
    h.valve_overlap_edge_radius = form == 0 ? 0.0 : 0.5 * h.valve_overlap;  // worn, rounded lands
    a.form = form == 0 ? "sharp" : "rounded";
    a.truth = {{"overlap", h.valve_overlap}};
    a.description = form == 0 ? "sharp spool overlap (no metering inside +-overlap)"
                              : "spool overlap with rounded metering edges (radius half the overlap)";
  } else if (cause == "entrained_air") {
    // alpha 0.15 at atmosphere: -27 % bulk modulus at the cap side's ~75 bar.
    // Adiabatic bubbles are stiffer: a little more air for a like size.
    h.air_fraction = (form == 0 ? 0.15 : 0.2) * level;
    h.air_polytropic_index = form == 0 ? 1.0 : 1.4;
    a.form = form == 0 ? "isothermal" : "adiabatic";
    const double e = c.quarter_car.bulk_modulus;
    const double e75 = mixture_bulk_modulus(e, h.air_fraction, h.air_polytropic_index, 75e5);  // the plant's own law
    a.truth = {{"air_fraction", h.air_fraction}, {"beta_at_75bar", e75}, {"beta_ratio_at_75bar", e75 / e}};
    a.description = std::string("free air in the oil: pressure-dependent effective bulk modulus (") +
                    (form == 0 ? "isothermal" : "adiabatic") + " mixture law)";
  } else if (cause == "sensor_delay") {
    // 6 ms strong (2.4 periods; an LVDT demodulator filter): not a whole number of samples.
    // Form 1: a conditioning filter of the same low-frequency group delay.
    const double tau = 0.006 * level;
    for (const char* ch : {"x_w", "x_b"}) {
      if (form == 0) c.sensors[ch].delay_s = tau;
      else c.sensors[ch].filter_hz = ConditioningFilter::cutoff_for_delay(tau);
    }
    a.form = form == 0 ? "pure_delay" : "butterworth_filter";
    a.truth = {{"tau", tau}};
    a.description = form == 0 ? "x_w and x_b transducers late by tau (cubic interpolation of the true signal's history)"
                              : "x_w and x_b through a 2nd-order Butterworth conditioning filter of group delay tau";
  } else if (cause == "sensor_offset") {
    const double b = 2e-3 * level;  // 2 mm on an LVDT: a zero not reset after a fixture change
    c.sensors[form == 0 ? "x_b" : "x_w"].offset = form == 0 ? b : -b;
    a.form = form == 0 ? "body_lvdt" : "wheel_lvdt";
    a.truth = {{form == 0 ? "b_b" : "b_w", form == 0 ? b : -b}};
    a.description = form == 0 ? "offset on the x_b transducer" : "offset on the x_w transducer";
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
    h.tyre_damping_in_contact_only = form == 1;
    a.form = form == 0 ? "no_pull" : "no_pull_no_damper";
    a.truth = {{"pull_loss", h.tyre_pull_loss}};
    a.description = form == 0 ? "wheel-hop burst in the demand and a tyre that cannot pull (weak: part of the pull lost)"
                              : "wheel-hop burst in the demand, a tyre that cannot pull and whose damping acts only in contact";
  } else if (cause == "damper_asymmetry") {
    // Rebound 1.6 x, compression 0.4 x the nominal 260 N s/m (strong): a
    // typical road damper's rebound/compression ratio of 3-4.
    // Form 1: a progressive rebound valve, 1.3 x at rest growing by 3 per m/s.
    h.damper_rebound_factor = 1.0 + (form == 0 ? 0.6 : 0.3) * level;
    h.damper_rebound_progression = form == 0 ? 0.0 : 3.0 * level;
    h.damper_compression_factor = 1.0 - 0.6 * level;
    a.form = form == 0 ? "piecewise_linear" : "progressive_rebound";
    const double bd = c.quarter_car.damper_damping;
    // The diagnosis fits bd + dc tanh(v_rel / 0.01): at speed, dc = (c_comp - c_reb) / 2.
    a.truth = {{"c_rebound", bd * h.damper_rebound_factor},
               {"c_compression", bd * h.damper_compression_factor},
               {"dc", 0.5 * bd * (h.damper_compression_factor - h.damper_rebound_factor)}};
    a.description = form == 0 ? "piecewise-linear damper: rebound and compression coefficients differ"
                              : "damper with a progressive rebound valve: rebound and compression coefficients differ";
  } else {
    throw std::invalid_argument("quarter_car has no effect '" + cause +
                                "' (bearing_friction, actuator_seal_friction, cross_port_leakage, valve_deadband, "
                                "entrained_air, sensor_delay, sensor_offset, tyre_liftoff, damper_asymmetry)");
  }
  return a;
}

// Every plant parameter within the tolerance; the PI gains within +-15 %
// (the loop's crossover moves 4 +- 0.6 Hz, far from the hydraulic mode); the
// demand table scaled 0.85-1.1 in amplitude (the largest demand, 0.125 m,
// stays inside the 0.17 m stroke) and 0.9-1.1 in time.
void perturb(RigConfig& c, Perturbation& d, const std::string& scratch) {
  auto& p = c.quarter_car;
  for (auto [name, v] : std::initializer_list<std::pair<const char*, double*>>{
           {"area_cap", &p.area_cap}, {"area_rod", &p.area_rod}, {"bulk_modulus", &p.bulk_modulus},
           {"supply_pressure", &p.supply_pressure}, {"valve_flow_gain", &p.valve_flow_gain},
           {"valve_time_constant", &p.valve_time_constant}, {"leakage_resistance", &p.leakage_resistance},
           {"dead_volume_cap", &p.dead_volume_cap}, {"dead_volume_rod", &p.dead_volume_rod},
           {"mass_rod", &p.mass_rod}, {"mass_wheel", &p.mass_wheel}, {"mass_body", &p.mass_body},
           {"rod_damping", &p.rod_damping}, {"tyre_stiffness", &p.tyre_stiffness},
           {"tyre_damping", &p.tyre_damping}, {"spring_stiffness", &p.spring_stiffness},
           {"damper_damping", &p.damper_damping}})
    d.scale(name, *v);
  d.scale("pi_kp", c.controller.pi.kp, 0.15);
  d.scale("pi_ki", c.controller.pi.ki, 0.15);
  if (d.active() && c.profile.type == ProfileKind::kCsv) {
    const double amp = d.factor("demand_amplitude", 0.85, 1.1), stretch = d.factor("demand_time", 0.9, 1.1);
    write_varied_demand(c.profile.csv_file, c.profile.csv_column, scratch + ".csv", amp, stretch);
    c.profile.csv_file = scratch + ".csv";
  }
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
      perturb,
  };
  return g;
}

}  // namespace rigctl
