#include "tools/iterate/diagnosis_model.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <functional>
#include <map>
#include <stdexcept>

namespace rigctl {

namespace {

using Setter = std::function<void(QuarterCarParams&, double)>;

// The diagnosis's quarter-car parameter names (tools/diagnosis/models/
// quarter_car.cpp) and where each goes in the plant's parameters.
const std::map<std::string, Setter>& quarter_car_setters() {
  static const std::map<std::string, Setter> s{
      {"ks", [](QuarterCarParams& p, double v) { p.spring_stiffness = v; }},
      {"bd", [](QuarterCarParams& p, double v) { p.damper_damping = v; }},
      {"Mb", [](QuarterCarParams& p, double v) { p.mass_body = v; }},
      {"Mw", [](QuarterCarParams& p, double v) { p.mass_wheel = v; }},
      {"kt", [](QuarterCarParams& p, double v) { p.tyre_stiffness = v; }},
      {"bt", [](QuarterCarParams& p, double v) { p.tyre_damping = v; }},
      {"kv_scale", [](QuarterCarParams& p, double v) { p.valve_flow_gain *= v; }},
      {"tau_r", [](QuarterCarParams& p, double v) { p.valve_time_constant = v; }},
      {"beta", [](QuarterCarParams& p, double v) { p.bulk_modulus = v; }},
      {"R_l", [](QuarterCarParams& p, double v) { p.leakage_resistance = v; }},
      {"Ps", [](QuarterCarParams& p, double v) { p.supply_pressure = v; }},
      {"A1", [](QuarterCarParams& p, double v) { p.area_cap = v; }},
      {"A2", [](QuarterCarParams& p, double v) { p.area_rod = v; }},
      {"Bvr", [](QuarterCarParams& p, double v) { p.rod_damping = v; }},
      {"V_dead", [](QuarterCarParams& p, double v) { p.dead_volume_cap = p.dead_volume_rod = v; }},
      // Effects: the cross-port leak as extra laminar conductance, entrained
      // air as a lower bulk modulus (applied after beta: the map is ordered
      // by name, so it is applied in a second pass below).
      {"C_il", [](QuarterCarParams& p, double v) { p.hidden.extra_laminar_leak = v; }},
      {"Fc", [](QuarterCarParams& p, double v) { p.bearing_friction.coulomb_base = v; }},
      {"dFs", [](QuarterCarParams& p, double v) { p.bearing_friction.stiction_excess = v; }},
      {"D", [](QuarterCarParams& p, double v) { p.bearing_friction.viscous = v; }},
      {"mu", [](QuarterCarParams& p, double v) { p.bearing_friction.normal_coefficient = v; }},
      {"delta", [](QuarterCarParams& p, double v) { p.hidden.valve_overlap = v; }},
      {"F_pr", [](QuarterCarParams& p, double v) { p.hidden.seal_preload = v; }},
      {"f_c", [](QuarterCarParams& p, double v) { p.hidden.seal_pressure_coefficient = v; }},
  };
  return s;
}

}  // namespace

DiagnosisModel diagnosis_model(const RigConfig& nominal, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(path + ": not a diagnosis JSON file: " + e.what());
  }
  if (!root.IsMap() || !root["rig"] || !root["final_parameters"] || !root["final_parameters"].IsMap()) {
    throw std::invalid_argument(path + ": not a diagnosis JSON file (needs the keys rig and final_parameters)");
  }
  const std::string rig = root["rig"].as<std::string>();
  if (rig != to_string(nominal.rig)) {
    throw std::invalid_argument(path + ": a diagnosis of " + rig + ", the config is a " + std::string(to_string(nominal.rig)));
  }
  if (nominal.rig != RigKind::kQuarterCar) {
    throw std::invalid_argument(path + ": only the quarter car's diagnosis parameters map onto its plant");
  }
  DiagnosisModel m{nominal, {}, {}};
  const auto& setters = quarter_car_setters();
  // The values the candidates' laws are written around (the diagnosis's
  // `model_constants`): the pressure sum the seal's level F_m is at, the
  // air's bubble index. A parameter whose constant the file lacks (a
  // diagnosis from before they were written) is ignored, not guessed.
  const YAML::Node constants = root["model_constants"];
  auto constant = [&](const char* key) { return constants && constants[key] ? constants[key].as<double>() : -1.0; };
  const double seal_sum = constant("P_m"), bubble_index = constant("air_bubble_index");
  double beta_ratio = 1.0;     // entrained air as a constant ratio (diagnoses before the mixture law)
  double seal_level = -1.0;    // F_m: the seal's Coulomb level at the pressure sum P_m
  for (const auto& kv : root["final_parameters"]) {
    const std::string name = kv.first.as<std::string>();
    const bool needs_constant = (name == "F_m" && seal_sum < 0.0) || (name == "alpha" && bubble_index < 0.0);
    if (kv.second.IsNull() || needs_constant) {  // undetermined, or not mappable: the config's value stays
      m.ignored.push_back(name);
      continue;
    }
    const double value = kv.second.as<double>();
    if (name == "beta_ratio") {
      beta_ratio = value;
      m.applied.push_back(name);
    } else if (name == "F_m") {
      seal_level = value;
      m.applied.push_back(name);
    } else if (name == "alpha") {  // entrained air by the mixture law, with the candidate's bubbles
      m.config.quarter_car.hidden.air_fraction = value;
      m.config.quarter_car.hidden.air_polytropic_index = bubble_index;
      m.applied.push_back(name);
    } else if (const auto it = setters.find(name); it != setters.end()) {
      it->second(m.config.quarter_car, value);
      m.applied.push_back(name);
    } else {
      m.ignored.push_back(name);
    }
  }
  auto& q = m.config.quarter_car;
  q.bulk_modulus *= beta_ratio;
  // The plant's seal law is a preload and a pressure term: the level F_m at
  // P_m less the term there.
  if (seal_level >= 0.0)
    q.hidden.seal_preload = std::max(0.0, seal_level - q.hidden.seal_pressure_coefficient * seal_sum);
  return m;
}

}  // namespace rigctl
