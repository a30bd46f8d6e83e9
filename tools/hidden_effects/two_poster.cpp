// Two-poster part of the hidden-effect generator (config/half_car_two_poster.yaml,
// plant/two_poster): the wear of either post's actuator, made by the post's
// own physics (plant/two_poster/hydraulic_post.*), on the post named by the
// cause's suffix (_1 front, _2 rear):
//   cross_port_leakage_N      form 0: turbulent leak through a worn piston seal
//                             (K sign(dp) sqrt|dp|, 2 x the nominal laminar
//                             leak at 50 bar); form 1: half laminar, half
//                             turbulent at 50 bar
//   actuator_seal_friction_N  the rod seal's Coulomb friction, 300 N strong,
//                             smoothed over 5 mm/s (form 0) or a sharper
//                             1 mm/s step (form 1)
//   entrained_air_N           free air in the oil (isothermal bubbles: the
//                             post's one air law), 15 % (form 0) or 20 %
//                             (form 1) at atmosphere, strong
// No diagnosis of the two-poster exists yet: the generator makes runs (and
// rigs for `rigctl iterate --effect`) whose posts differ from the nominal
// model, as a worn road simulator does.
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "tools/hidden_effects/perturbation.hpp"
#include "tools/hidden_effects/rigs.hpp"

namespace rigctl {

namespace {

void make_clean(RigConfig& c) {
  for (auto& p : c.two_poster.posts) {
    p.extra_laminar_leak = 0.0;
    p.worn_seal_orifice = 0.0;
    p.seal_friction = 0.0;
    p.air_fraction = 0.0;
  }
}

// "cross_port_leakage_2" -> {"cross_port_leakage", 1}; throws for no or a bad suffix.
std::pair<std::string, int> cause_and_post(const std::string& cause) {
  const auto underscore = cause.rfind('_');
  const std::string suffix = underscore == std::string::npos ? "" : cause.substr(underscore + 1);
  if (suffix != "1" && suffix != "2") {
    throw std::invalid_argument("two_poster: no hidden effect '" + cause +
                                "' (causes name their post: cross_port_leakage_1, actuator_seal_friction_2, entrained_air_1, ...)");
  }
  return {cause.substr(0, underscore), suffix == "1" ? 0 : 1};
}

AppliedEffect apply(RigConfig& c, const std::string& cause, double level, int form) {
  const auto [kind, post] = cause_and_post(cause);
  HydraulicPostParams& h = c.two_poster.posts[static_cast<std::size_t>(post)];
  const std::string which = post == 0 ? "the front post's" : "the rear post's";
  AppliedEffect a;
  a.cause = cause;
  a.level = level;
  if (kind == "cross_port_leakage") {
    // As the quarter car's worn seal: 2 x the nominal laminar leak at 50 bar.
    const double nominal_at_50bar = 50e5 / h.leakage_resistance;
    const double turbulent_share = form == 0 ? 1.0 : 0.5;
    h.worn_seal_orifice = turbulent_share * 2.0 * level * nominal_at_50bar / std::sqrt(50e5);
    h.extra_laminar_leak = (1.0 - turbulent_share) * 2.0 * level * nominal_at_50bar / 50e5;
    a.form = form == 0 ? "turbulent" : "laminar_turbulent";
    a.truth = {{"K_orifice", h.worn_seal_orifice}, {"extra_laminar_leak", h.extra_laminar_leak},
               {"extra_leak_at_50bar_m3_s", 2.0 * level * nominal_at_50bar}};
    a.description = which + (form == 0 ? " turbulent cross-port leak through a worn piston seal, K sign(dp) sqrt|dp|"
                                       : " cross-port leak through a worn piston seal, half laminar, half turbulent at 50 bar");
    return a;
  }
  if (kind == "actuator_seal_friction") {
    // 300 N: about 1 % of the post's ~30 kN rod force at 200 bar on its cap side.
    h.seal_friction = 300.0 * level;
    h.seal_velocity = form == 0 ? 0.005 : 0.001;
    a.form = form == 0 ? "coulomb_5mm_s" : "coulomb_1mm_s";
    a.truth = {{"seal_friction_n", h.seal_friction}, {"seal_velocity_m_s", h.seal_velocity}};
    a.description = which + " rod seal friction, Coulomb " + std::to_string(h.seal_friction) + " N smoothed over " +
                    std::to_string(h.seal_velocity) + " m/s";
    return a;
  }
  if (kind == "entrained_air") {
    h.air_fraction = (form == 0 ? 0.15 : 0.2) * level;
    a.form = form == 0 ? "isothermal_15" : "isothermal_20";
    a.truth = {{"air_fraction", h.air_fraction}};
    a.description = which + " oil with " + std::to_string(h.air_fraction) + " free air at atmosphere (isothermal bubbles)";
    return a;
  }
  throw std::invalid_argument("two_poster: no hidden effect '" + cause + "'");
}

// Every vehicle parameter and each post's oil, valve, leak and platen within the tolerance.
void perturb(RigConfig& c, Perturbation& d, const std::string& /*scratch*/) {
  auto& car = c.two_poster.car;
  for (auto [name, v] : std::initializer_list<std::pair<const char*, double*>>{
           {"mass_body", &car.mass_body}, {"inertia_body", &car.inertia_body}, {"mass_unsprung_1", &car.mass_unsprung_1},
           {"mass_unsprung_2", &car.mass_unsprung_2}, {"spring_1", &car.spring_1}, {"spring_2", &car.spring_2},
           {"damper_1", &car.damper_1}, {"damper_2", &car.damper_2}, {"tyre_stiffness_1", &car.tyre_stiffness_1},
           {"tyre_stiffness_2", &car.tyre_stiffness_2}})
    d.scale(name, *v);
  for (std::size_t i = 0; i < 2; ++i) {
    auto& h = c.two_poster.posts[i];
    const std::string n = "_" + std::to_string(i + 1);
    d.scale("bulk_modulus" + n, h.bulk_modulus);
    d.scale("valve_flow_gain" + n, h.valve_flow_gain);
    d.scale("leakage_resistance" + n, h.leakage_resistance);
    d.scale("mass_platen" + n, h.mass_platen);
    d.scale("rod_damping" + n, h.rod_damping);
  }
}

}  // namespace

const RigEffectGenerator& two_poster_effect_generator() {
  static const RigEffectGenerator g{
      RigKind::kTwoPoster,
      {"cross_port_leakage_1", "cross_port_leakage_2", "actuator_seal_friction_1", "actuator_seal_friction_2",
       "entrained_air_1", "entrained_air_2"},
      "",
      make_clean,
      apply,
      perturb,
  };
  return g;
}

}  // namespace rigctl
