// The `plant:` section of the two-poster (docs/rig-models.md 4): the half
// car of seed 001 (its body, axles, springs, dampers and tyres) and the two
// hydraulic posts under its tyres, each like the quarter car's actuator with
// the hidden effects it may carry. SI throughout; every key is required
// except a post's hidden effects (0 when absent).
#include "config/plant_readers.hpp"

namespace rigctl {

namespace {

void read_axle(ConfigReader r, double& unsprung, double& spring, double& damper, double& tyre_k, double& tyre_c) {
  unsprung = r.number("unsprung_mass_kg", 1e-3, 1e5);
  spring = r.number("spring_n_per_m", 0.0, 1e9);
  damper = r.number("damper_n_s_per_m", 0.0, 1e9);
  tyre_k = r.number("tyre_stiffness_n_per_m", 1.0, 1e10);
  tyre_c = r.number("tyre_damping_n_s_per_m", 0.0, 1e9);
  r.reject_unknown_keys();
}

void read_post(ConfigReader r, HydraulicPostParams& p) {
  p.area_cap = r.number("area_cap_m2", 1e-6, 1.0);
  p.area_rod = r.number("area_rod_m2", 1e-6, 1.0);
  if (p.area_rod >= p.area_cap) r.fail("area_rod_m2", "rod-side area must be smaller than the cap-side area");
  p.bulk_modulus = r.number("bulk_modulus_pa", 1e6, 1e11);
  p.supply_pressure = r.number("supply_pressure_pa", 1e5, 1e9);
  p.valve_flow_gain = r.number("valve_flow_gain", 1e-12, 1e-2);
  p.valve_time_constant = r.number("valve_time_constant_s", 1e-5, 1.0);
  p.laminar_pressure = r.number("laminar_pressure_pa", 1.0, 1e8);
  p.cavitation_pressure = r.number("cavitation_pressure_pa", -1.01325e5, 0.0);
  p.leakage_resistance = r.number("leakage_resistance", 1e6, 1e20);
  p.dead_volume = r.number("dead_volume_m3", 1e-9, 1.0);
  p.stroke_min = r.number("stroke_min_m", -10.0, 10.0);
  p.stroke_max = r.number("stroke_max_m", -10.0, 10.0);
  if (p.stroke_max <= p.stroke_min) r.fail("stroke_max_m", "must be greater than stroke_min_m");
  p.end_stop_stiffness = r.number("end_stop_stiffness", 0.0, 1e12);
  p.end_stop_damping = r.number("end_stop_damping", 0.0, 1e9);
  p.mass_platen = r.number("mass_platen_kg", 1e-3, 1e6);
  p.rod_damping = r.number("rod_damping", 0.0, 1e9);
  // Hidden effects (`rigctl make-run` sets them; a nominal rig has none).
  if (r.has("extra_laminar_leak")) p.extra_laminar_leak = r.number("extra_laminar_leak", 0.0, 1.0);
  if (r.has("worn_seal_orifice")) p.worn_seal_orifice = r.number("worn_seal_orifice", 0.0, 1.0);
  if (r.has("seal_friction_n")) p.seal_friction = r.number("seal_friction_n", 0.0, 1e7);
  if (r.has("seal_velocity_m_s")) p.seal_velocity = r.number("seal_velocity_m_s", 1e-6, 10.0);
  if (r.has("air_fraction")) p.air_fraction = r.number("air_fraction", 0.0, 0.5);
  r.reject_unknown_keys();
}

}  // namespace

void read_two_poster_plant(ConfigReader r, TwoPosterParams& p) {
  p.substep_s = r.number("substep_s", 1e-6, 1e-2);
  auto car = r.child("car");
  HalfCarParams& c = p.car;
  c.mass_body = car.number("mass_body_kg", 1.0, 1e6);
  c.inertia_body = car.number("pitch_inertia_kg_m2", 1e-3, 1e7);
  c.dist_front = car.number("dist_front_m", 1e-3, 100.0);
  c.dist_rear = car.number("dist_rear_m", 1e-3, 100.0);
  c.gravity = car.number("gravity", 0.0, 100.0);
  read_axle(car.child("front"), c.mass_unsprung_1, c.spring_1, c.damper_1, c.tyre_stiffness_1, c.tyre_damping_1);
  read_axle(car.child("rear"), c.mass_unsprung_2, c.spring_2, c.damper_2, c.tyre_stiffness_2, c.tyre_damping_2);
  car.reject_unknown_keys();
  auto posts = r.items("posts");
  if (posts.size() != 2) r.fail("posts", "expected two posts (front, rear), got " + std::to_string(posts.size()));
  for (std::size_t i = 0; i < 2; ++i) read_post(posts[i], p.posts[i]);
  r.reject_unknown_keys();
}

}  // namespace rigctl
