#include "config/rig_config.hpp"

#include <filesystem>
#include <numbers>

#include "config/config_reader.hpp"

namespace rigctl {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

LoopConfig read_loop(ConfigReader r) {
  LoopConfig c;
  c.period_s = r.number("period_s", 1e-4, 0.1);
  try {
    c.overrun_policy = overrun_policy_from_string(r.choice("overrun_policy", {"skip", "catch_up"}));
  } catch (const std::invalid_argument& e) {
    r.fail("overrun_policy", e.what());
  }
  c.timing_publish_s = r.number("timing_publish_s", c.period_s, 3600.0);
  auto rt = r.child("realtime");
  c.realtime.enabled = rt.boolean("enabled");
  c.realtime.priority = static_cast<int>(rt.integer("priority", 1, 99));
  c.realtime.lock_memory = rt.boolean("lock_memory");
  c.realtime.cpu = static_cast<int>(rt.integer("cpu", -1, 1023));
  c.realtime.hold_cpu_dma_latency = rt.boolean("hold_cpu_dma_latency");
  rt.reject_unknown_keys();
  r.reject_unknown_keys();
  return c;
}

TelemetryConfig read_telemetry(ConfigReader r) {
  TelemetryConfig c;
  c.lcm_url = r.text("lcm_url");
  if (c.lcm_url.find("://") == std::string::npos) r.fail("lcm_url", "expected a URL such as memq:// or udpm://ADDR:PORT?ttl=0");
  c.channel_prefix = r.text("channel_prefix");
  c.log_dir = r.text("log_dir");
  r.reject_unknown_keys();
  return c;
}

ControllerConfig read_controller(ConfigReader r, double period_s) {
  ControllerConfig c;
  c.type = r.choice("type", {"pi"});
  c.feedback = r.text("feedback");
  c.output = r.text("output");
  c.pi.kp = r.number("kp", 0.0, 1e6);
  c.pi.ki = r.number("ki", 0.0, 1e6);
  c.pi.output_limit = r.number("output_limit", 1e-6, 1e6);
  c.pi.anti_windup = r.choice("anti_windup", {"conditional", "none"}) == "none" ? AntiWindup::kNone
                                                                              : AntiWindup::kConditional;
  c.pi.period_s = period_s;
  r.reject_unknown_keys();
  return c;
}

ProfileConfig read_profile(ConfigReader r, const std::string& config_file) {
  ProfileConfig c;
  c.type = r.choice("type", {"ramp_steps", "sine", "csv"});
  c.filter_tau_s = r.number("filter_tau_s", 0.0, 100.0);
  if (c.type == "csv") {
    const std::filesystem::path file = r.text("file");
    c.csv_file = file.is_absolute() ? file.string()
                                    : (std::filesystem::path(config_file).parent_path() / file).string();
    c.csv_column = r.text("column");
  } else {
    c.start = r.number("start_m", -10.0, 10.0);
    c.hold_s = r.number("hold_s", 0.0, 1e5);
    c.ramp_target = r.number("ramp_target_m", -10.0, 10.0);
    c.ramp_rate = r.number("ramp_rate_m_s", 1e-6, 100.0);
    if (c.type == "ramp_steps") {
      c.steps = r.numbers("steps_m", 1, 10000, -10.0, 10.0);
      c.step_hold_s = r.number("step_hold_s", 1e-3, 1e5);
    } else {
      c.amplitude = r.number("amplitude_m", 0.0, 10.0);
      c.frequency_hz = r.number("frequency_hz", 1e-4, 1e3);
      c.cycles = r.number("cycles", 0.0, 1e7);
    }
  }
  r.reject_unknown_keys();
  return c;
}

std::vector<LimitConfig> read_limits(ConfigReader r) {
  std::vector<LimitConfig> out;
  for (const auto& channel : r.keys()) {
    const auto range = r.numbers(channel, 2, 2);
    if (!(range[0] < range[1])) r.fail(channel, "limit range must be [min, max] with min < max");
    out.push_back({channel, range[0], range[1]});
  }
  return out;
}

void read_quarter_car_plant(ConfigReader r, QuarterCarParams& p) {
  p.substeps = static_cast<int>(r.integer("substeps", 1, 10000));
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

std::map<std::string, SensorSpec> read_sensors(ConfigReader r) {
  std::map<std::string, SensorSpec> out;
  for (const auto& channel : r.keys()) {
    auto s = r.child(channel);
    SensorSpec spec;
    spec.noise_sd = s.number("noise_sd", 0.0, kInf);
    spec.bits = static_cast<int>(s.integer("bits", 0, 32));
    const auto range = s.numbers("range", 2, 2);
    if (!(range[0] < range[1])) s.fail("range", "must be [min, max] with min < max");
    spec.range_min = range[0];
    spec.range_max = range[1];
    spec.offset = s.number("offset");
    s.reject_unknown_keys();
    out[channel] = spec;
  }
  return out;
}

RigConfig parse(ConfigReader root) {
  RigConfig c;
  c.file = root.file();
  c.rig = root.choice("rig", known_rig_kinds());
  c.driver = root.choice("driver", {"sim"});
  c.seed = static_cast<uint64_t>(root.integer("seed", 0, std::numeric_limits<int64_t>::max()));
  c.loop = read_loop(root.child("loop"));
  c.telemetry = read_telemetry(root.child("telemetry"));
  c.controller = read_controller(root.child("controller"), c.loop.period_s);
  c.profile = read_profile(root.child("profile"), c.file);
  if (root.has("limits")) c.limits = read_limits(root.child("limits"));
  read_quarter_car_plant(root.child("plant"), c.quarter_car);
  c.sensors = read_sensors(root.child("sensors"));
  root.reject_unknown_keys();
  return c;
}

}  // namespace

RigConfig load_rig_config(const std::string& path) { return parse(ConfigReader::load(path)); }

RigConfig parse_rig_config(const std::string& yaml_text, const std::string& name) {
  return parse(ConfigReader::from_string(yaml_text, name));
}

}  // namespace rigctl
