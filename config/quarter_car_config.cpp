#include <numbers>

#include "config/plant_readers.hpp"

namespace rigctl {

void read_quarter_car_plant(ConfigReader r, QuarterCarParams& p) {
  p.substeps = static_cast<int>(r.integer("substeps", 0, 10000));  // 0: from the fastest mode
  auto h = r.child("hydraulics");
  p.area_cap = h.number("area_cap_m2", 1e-6, 1.0);
  p.area_rod = h.number("area_rod_m2", 1e-6, 1.0);
  if (p.area_rod >= p.area_cap) h.fail("area_rod_m2", "rod-side area must be smaller than the cap-side area");
  p.bulk_modulus = h.number("bulk_modulus_pa", 1e6, 1e11);
  p.supply_pressure = h.number("supply_pressure_pa", 1e5, 1e9);
  p.valve_flow_gain = h.number("valve_flow_gain", 1e-12, 1e-2);
  p.valve_time_constant = h.number("valve_time_constant_s", 1e-5, 1.0);
  p.laminar_pressure = h.number("laminar_pressure_pa", 1.0, 1e8);
  p.cavitation_pressure = h.number("cavitation_pressure_pa", -1.01325e5, 0.0);
  p.leakage = h.boolean("leakage");
  p.leakage_resistance = h.number("leakage_resistance", 1e6, 1e20);
  p.dead_volume_cap = h.number("dead_volume_cap_m3", 1e-9, 1.0);
  p.dead_volume_rod = h.number("dead_volume_rod_m3", 1e-9, 1.0);
  p.stroke_min = h.number("stroke_min_m", -10.0, 10.0);
  p.stroke_max = h.number("stroke_max_m", -10.0, 10.0);
  if (p.stroke_max <= p.stroke_min) h.fail("stroke_max_m", "must be greater than stroke_min_m");
  p.end_stop_stiffness = h.number("end_stop_stiffness", 0.0, 1e12);
  p.end_stop_damping = h.number("end_stop_damping", 0.0, 1e9);
  h.reject_unknown_keys();

  auto m = r.child("mechanics");
  p.mass_rod = m.number("mass_rod_kg", 1e-3, 1e6);
  p.mass_wheel = m.number("mass_wheel_kg", 1e-3, 1e6);
  p.mass_body = m.number("mass_body_kg", 1e-3, 1e6);
  p.rod_damping = m.number("rod_damping", 0.0, 1e9);
  p.tyre_stiffness = m.number("tyre_stiffness", 1.0, 1e12);
  p.tyre_damping = m.number("tyre_damping", 0.0, 1e9);
  p.spring_stiffness = m.number("spring_stiffness", 1.0, 1e12);
  p.damper_damping = m.number("damper_damping", 0.0, 1e9);
  p.gravity = m.number("gravity", 0.0, 100.0);
  m.reject_unknown_keys();

  auto f = r.child("bearing_friction");
  auto& b = p.bearing_friction;
  b.enabled = f.boolean("enabled");
  b.coulomb_base = f.number("coulomb_base_n", 0.0, 1e7);
  b.normal_coefficient = f.number("normal_coefficient", 0.0, 10.0);
  b.normal_force_dependent = f.boolean("normal_force_dependent");
  b.stiction_excess = f.number("stiction_excess_n", 0.0, 1e7);
  b.stribeck_velocity = f.number("stribeck_velocity_m_s", 1e-6, 100.0);
  b.stribeck_exponent = f.number("stribeck_exponent", 0.1, 10.0);
  b.viscous = f.number("viscous", 0.0, 1e9);
  b.construction_angle = f.number("construction_angle_deg", 1.0, 89.0) * std::numbers::pi / 180.0;
  b.damper_free_length = f.number("damper_free_length_m", 1e-3, 100.0);
  f.reject_unknown_keys();
  r.reject_unknown_keys();
}

}  // namespace rigctl
