#include "config/plant_readers.hpp"

namespace rigctl {

void read_pneumatic_rotary_plant(ConfigReader r, PneumaticRotaryParams& p) {
  p.substeps = static_cast<int>(r.integer("substeps", 1, 10000));
  auto v = r.child("valve");
  p.solenoid_gain = v.number("solenoid_gain_m_per_v", 1e-9, 1e-1);
  p.spool_limit = v.number("spool_limit_m", 1e-7, 1e-1);
  p.valve_null_offset = v.number("null_offset_v", -10.0, 10.0);
  p.flow_gain = v.number("flow_gain", 1e-6, 1e6);
  p.flow_pressure_coefficient = v.number("flow_pressure_coefficient", 0.0, 1e-3);
  p.dither = v.boolean("dither");
  p.dither_amplitude = v.number("dither_amplitude_v", 0.0, 10.0);
  p.dither_frequency = v.number("dither_frequency_hz", 0.1, 1000.0);
  v.reject_unknown_keys();

  auto c = r.child("chambers");
  p.chamber_volume = c.number("volume_m3", 1e-7, 1.0);
  p.quiescent_pressure = c.number("quiescent_pressure_pa", 1e4, 1e7);
  p.supply_temperature = c.number("supply_temperature_k", 100.0, 1000.0);
  p.heat_capacity_ratio = c.number("heat_capacity_ratio", 1.0, 1.67);
  p.gas_constant = c.number("gas_constant", 1.0, 1e4);
  c.reject_unknown_keys();

  auto l = r.child("load");
  p.first_moment = l.number("first_moment_m3_per_rad", 1e-7, 1.0);
  p.inertia = l.number("inertia_kg_m2", 1e-4, 1e4);
  p.max_torque = l.number("max_torque_nm", 1e-3, 1e6);
  p.angle_limit = l.number("angle_limit_rad", 1e-3, 10.0);
  p.end_stop_stiffness = l.number("end_stop_stiffness", 0.0, 1e9);
  p.end_stop_damping = l.number("end_stop_damping", 0.0, 1e9);
  l.reject_unknown_keys();

  // Levels in per cent of maximum torque, as the paper gives them.
  auto h = r.child("bladder_hysteresis");
  p.hysteresis.enabled = h.boolean("enabled");
  p.hysteresis.level = h.number("level_percent", 0.0, 100.0) / 100.0;
  p.hysteresis.step_fraction = h.number("step_fraction", 0.0, 1.0);
  p.hysteresis.boundary_angle = h.number("boundary_angle_rad", 1e-6, 10.0);
  h.reject_unknown_keys();

  auto b = r.child("coulomb_brake");
  p.brake.enabled = b.boolean("enabled");
  p.brake.level = b.number("level_percent", 0.0, 100.0) / 100.0;
  b.reject_unknown_keys();
  r.reject_unknown_keys();
}

}  // namespace rigctl
