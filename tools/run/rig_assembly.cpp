#include "tools/run/rig_assembly.hpp"

#include <algorithm>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "drivers/hardware_driver.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "plant/half_car/half_car_plant.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_plant.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "plant/two_poster/two_poster_plant.hpp"
#include "rt/control/fuzzy_suspension_controller.hpp"
#include "rt/control/lqr_controller.hpp"
#include "rt/control/pi_controller.hpp"
#include "rt/control/pvp_controller.hpp"
#include "rt/control/skyhook_controller.hpp"
#include "rt/control/suspension_controller.hpp"

namespace rigctl {

namespace {

[[noreturn]] void config_fail(const RigConfig& c, const std::string& key, const std::string& reason) {
  throw ConfigError(c.file + ": " + key + ": " + reason);
}

std::string channel_list(const std::vector<ChannelInfo>& channels) {
  std::string s;
  for (const auto& ch : channels) s += (s.empty() ? "" : ", ") + ch.name;
  return s;
}

bool is_truth_channel(const std::string& name) { return name.rfind("sim_", 0) == 0; }

std::vector<SensorSpec> sensor_specs(const RigConfig& c, const std::vector<ChannelInfo>& signals) {
  for (const auto& [name, spec] : c.sensors) {
    bool found = false;
    for (const auto& s : signals) found = found || (s.name == name && !is_truth_channel(name));
    if (!found) config_fail(c, "sensors." + name, "no such sensor channel on this rig (channels: " + channel_list(signals) + ")");
  }
  std::vector<SensorSpec> out;
  for (const auto& s : signals) {
    if (is_truth_channel(s.name)) {
      out.emplace_back();  // simulator truth: exact
      continue;
    }
    const auto it = c.sensors.find(s.name);
    if (it == c.sensors.end()) config_fail(c, "sensors." + s.name, "missing required key (a sensor model for every channel)");
    out.push_back(it->second);
  }
  return out;
}

std::vector<SensorSpec> dac_specs(const RigConfig& c, const std::vector<ChannelInfo>& commands) {
  for (const auto& [name, spec] : c.dacs) {
    bool found = false;
    for (const auto& s : commands) found = found || s.name == name;
    if (!found) config_fail(c, "outputs." + name, "no such output on this rig (outputs: " + channel_list(commands) + ")");
  }
  std::vector<SensorSpec> out;
  for (const auto& s : commands) {
    const auto it = c.dacs.find(s.name);
    if (it == c.dacs.end()) config_fail(c, "outputs." + s.name, "missing required key (a converter for every output)");
    out.push_back(it->second);
  }
  return out;
}

}  // namespace

std::unique_ptr<SimulatedPlant> make_plant(const RigConfig& c) {
  switch (c.rig) {
    case RigKind::kQuarterCar: return std::make_unique<QuarterCarPlant>(c.quarter_car);
    case RigKind::kPneumaticRotary: return std::make_unique<PneumaticRotaryPlant>(c.pneumatic_rotary);
    case RigKind::kHalfCar: return std::make_unique<HalfCarPlant>(c.half_car);
    case RigKind::kTwoPoster: return std::make_unique<TwoPosterPlant>(c.two_poster);
  }
  throw std::logic_error("make_plant: rig kind out of range");
}

namespace {

// The Modbus DAQ, with the valve on CANopen when `valve` is given.
std::unique_ptr<Driver> make_hardware_driver(const RigConfig& c, const std::optional<CanopenValveConfig>& valve) {
  try {
    return std::make_unique<HardwareDriver>(*c.modbus, valve, c.driver_start_timeout_s);
  } catch (const std::invalid_argument& e) {
    config_fail(c, "modbus", e.what());
  }
}

std::unique_ptr<Driver> make_sim_driver(const RigConfig& c) {
  auto plant = make_plant(c);
  auto sensors = sensor_specs(c, plant->signals());
  auto dacs = dac_specs(c, plant->commands());
  // Both rigs' safe output is 0: valve at null (servovalve current, solenoid voltage).
  std::vector<double> safe(plant->commands().size(), 0.0);
  return std::make_unique<SimDriver>(std::move(plant), std::move(sensors), std::move(dacs), c.loop.period_s, c.seed,
                                     std::move(safe));
}

std::unique_ptr<Driver> make_driver(const RigConfig& c) {
  switch (c.driver) {
    case DriverKind::kSim: return make_sim_driver(c);
    case DriverKind::kModbus: return make_hardware_driver(c, std::nullopt);
    case DriverKind::kModbusCanopen: return make_hardware_driver(c, c.canopen);
  }
  throw std::logic_error("make_driver: driver kind out of range");
}

int required_input(const RigConfig& c, const ChannelLayout& layout, const std::string& key, const std::string& name) {
  const int index = layout.input_index(name);
  if (index < 0) {
    config_fail(c, key, "unknown input channel '" + name + "' (inputs: " + channel_list(layout.inputs) + ")");
  }
  return index;
}

int required_output(const RigConfig& c, const ChannelLayout& layout, const std::string& key, const std::string& name) {
  const int index = layout.output_index(name);
  if (index < 0) {
    config_fail(c, key, "unknown output channel '" + name + "' (outputs: " + channel_list(layout.outputs) + ")");
  }
  return index;
}

// The half car's controllers (plant/half_car/half_car_params.hpp for the geometry):
// the body states by their run-file names, the regulated heave from
// controller.feedback, the two actuator forces from output_1/output_2.
std::unique_ptr<Controller> make_suspension_controller(const RigConfig& c, const ChannelLayout& layout) {
  const auto& s = c.controller.suspension;
  SuspensionChannels ch;
  ch.z_s = required_input(c, layout, "controller.feedback", c.controller.feedback);
  auto input = [&](const char* name) {
    return required_input(c, layout, std::string("controller (body state ") + name + ")", name);
  };
  ch.phi = input("phi");
  ch.z_u1 = input("z_u1");
  ch.z_u2 = input("z_u2");
  ch.z_s_dot = input("z_s_dot");
  ch.z_s_ddot = input("z_s_ddot");
  ch.phi_dot = input("phi_dot");
  ch.phi_ddot = input("phi_ddot");
  ch.z_u1_dot = input("z_u1_dot");
  ch.z_u2_dot = input("z_u2_dot");
  ch.output_1 = required_output(c, layout, "controller.output_1", s.output_1);
  ch.output_2 = required_output(c, layout, "controller.output_2", s.output_2);
  if (ch.output_1 == ch.output_2) config_fail(c, "controller.output_2", "must differ from output_1");
  // The output converters must pass the largest force the controller sends.
  for (const auto& name : {s.output_1, s.output_2}) {
    const auto it = c.dacs.find(name);
    if (is_simulated(c.driver) && it != c.dacs.end() &&
        (it->second.range_min > -s.force_limit || it->second.range_max < s.force_limit)) {
      config_fail(c, "controller.force_limit_n", "+-" + std::to_string(s.force_limit) + " N is outside outputs." +
                                                     name + ".range");
    }
  }
  const LeverArms lever{half_car_lever_arm(c.half_car, 0), half_car_lever_arm(c.half_car, 1)};
  try {
    switch (c.controller.type) {
      case ControllerKind::kPassive: return std::make_unique<PassiveSuspensionController>(ch);
      case ControllerKind::kFuzzy: {
        FuzzySuspensionConfig f;
        f.engine = s.fuzzy;
        f.first_input = s.fuzzy_first_input;
        f.force_limit = s.force_limit;
        f.lever_arm = lever;
        f.channels = ch;
        return std::make_unique<FuzzySuspensionController>(f);
      }
      case ControllerKind::kSkyhook: {
        SkyhookConfig k;
        k.c_sky = s.skyhook_c_sky;
        k.force_limit = s.force_limit;
        k.lever_arm = lever;
        k.channels = ch;
        return std::make_unique<SkyhookController>(k);
      }
      case ControllerKind::kLqr: {
        LqrConfig q = LqrConfig::from_design(c.half_car, s.lqr, s.force_limit);
        q.channels = ch;
        return std::make_unique<LqrController>(q);
      }
      case ControllerKind::kPi:
      case ControllerKind::kPvp:
        break;  // not the half car's: the loader refuses them there (rig_of)
    }
  } catch (const std::exception& e) {
    config_fail(c, "controller." + std::string(to_string(c.controller.type)), e.what());
  }
  throw std::logic_error("make_suspension_controller: " + std::string(to_string(c.controller.type)) +
                         " is not a half-car controller");
}

// The output of the single-output controllers (pi, pvp).
int controller_output(const RigConfig& c, const ChannelLayout& layout) {
  const int output = layout.output_index(c.controller.output);
  if (output < 0) {
    config_fail(c, "controller.output", "unknown output channel '" + c.controller.output + "' (outputs: " +
                                             channel_list(layout.outputs) + ")");
  }
  return output;
}

std::unique_ptr<Controller> make_controller(const RigConfig& c, const ChannelLayout& layout) {
  switch (c.controller.type) {
    case ControllerKind::kPi: {
      const int output = controller_output(c, layout);
      PiConfig pi = c.controller.pi;
      pi.feedback_input = required_input(c, layout, "controller.feedback", c.controller.feedback);
      pi.output_index = output;
      return std::make_unique<PiController>(pi);
    }
    case ControllerKind::kPvp: {
      const int output = controller_output(c, layout);
      PvpConfig pvp = c.controller.pvp;
      pvp.angle_input = required_input(c, layout, "controller.feedback", c.controller.feedback);
      pvp.pressure_input = required_input(c, layout, "controller.pressure", c.controller.pressure);
      pvp.output_index = output;
      return std::make_unique<PvpController>(pvp);
    }
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: return make_suspension_controller(c, layout);
  }
  throw std::logic_error("make_controller: controller kind out of range");
}

}  // namespace

std::unique_ptr<FilteredProfile> make_profile(const RigConfig& c, double& duration) {
  const auto& p = c.profile;
  std::unique_ptr<SetpointProfile> raw;
  const LeadIn lead{p.start, p.ramp_target, p.hold_s, p.ramp_rate};
  switch (p.type) {
    case ProfileKind::kHold:
      raw = std::make_unique<HoldProfile>(p.value, p.duration_s);
      break;
    case ProfileKind::kRampSteps:
      raw = std::make_unique<RampStepsProfile>(lead, p.steps, p.step_hold_s);
      break;
    case ProfileKind::kSine:
      raw = std::make_unique<SineProfile>(lead, p.amplitude, p.frequency_hz, p.cycles);
      break;
    case ProfileKind::kCsv:
      try {
        raw = std::make_unique<TableProfile>(TableProfile::from_csv(p.csv_file, p.csv_column));
      } catch (const std::exception& e) {
        config_fail(c, "profile.file", e.what());
      }
      break;
  }
  duration = raw->duration();
  return std::make_unique<FilteredProfile>(std::move(raw), p.filter_tau_s, c.loop.period_s);
}

namespace {

// Order matters: the first of the most severe trips names why a run ended.
// Plausibility of every input first, then `limits:`, then `safety.detectors`
// in file order.
LimitDetectors make_detectors(const RigConfig& c, const ChannelLayout& layout, int feedback) {
  std::vector<DetectorSpec> specs;
  for (std::size_t i = 0; i < layout.inputs.size(); ++i) {
    DetectorSpec s;
    s.name = "invalid." + layout.inputs[i].name;
    s.kind = DetectorKind::kInvalid;
    s.channel = static_cast<int>(i);
    specs.push_back(s);
  }
  for (const auto& l : c.limits) {
    DetectorSpec s;
    s.name = "limits." + l.channel;
    s.kind = DetectorKind::kRange;
    s.channel = required_input(c, layout, "limits." + l.channel, l.channel);
    s.min = l.min;
    s.max = l.max;
    s.action = c.safety.limits_action;
    specs.push_back(s);
  }
  for (const auto& d : c.safety.detectors) {
    const std::string key = "safety.detectors." + d.name;
    DetectorSpec s;
    s.name = key;
    s.kind = d.type;
    s.min = d.min;
    s.max = d.max;
    s.duration_s = d.duration_s;
    s.tolerance = d.tolerance;
    s.command_min = d.command_min;
    s.max_count = d.max_count;
    s.window_s = d.window_s;
    s.action = d.action;
    s.latch = d.latch;
    switch (s.kind) {
      case DetectorKind::kTrackingError:  // default: the controller's feedback
        s.channel = d.channel.empty() ? feedback : required_input(c, layout, key + ".channel", d.channel);
        break;
      case DetectorKind::kValveSaturation:
        s.channel = required_output(c, layout, key + ".output", d.output);
        break;
      case DetectorKind::kStuck:  // the input that should move while its output commands it
        s.channel = required_input(c, layout, key + ".channel", d.channel);
        s.command_output = required_output(c, layout, key + ".output", d.output);
        break;
      case DetectorKind::kInvalid:  // (built above for every input, never configured)
      case DetectorKind::kRange:
      case DetectorKind::kRate:
      case DetectorKind::kOpenCircuit:
        s.channel = required_input(c, layout, key + ".channel", d.channel);
        break;
      case DetectorKind::kSampleAge:  // the sample's time stamp
      case DetectorKind::kOverruns:   // the loop's count
        break;
    }
    specs.push_back(s);
  }
  try {
    return LimitDetectors(std::move(specs), layout.inputs.size(), feedback, c.loop.period_s);
  } catch (const std::invalid_argument& e) {
    config_fail(c, "safety.detectors", e.what());
  }
}

SafetyOptions make_safety(const RigConfig& c, int feedback) {
  SafetyOptions s;
  s.auto_sequence = c.safety.auto_sequence;
  s.feedback_input = feedback;
  s.machine.period_s = c.loop.period_s;
  s.machine.low_settle_s = c.safety.low_settle_s;
  s.machine.high_settle_s = c.safety.high_settle_s;
  s.machine.hold_deceleration = c.safety.hold_deceleration;
  s.machine.setpoint_rate = c.safety.setpoint_rate;
  s.machine.setpoint_min = c.safety.setpoint_min;
  s.machine.setpoint_max = c.safety.setpoint_max;
  s.machine.stop_timeout_s = c.safety.stop_timeout_s;
  return s;
}

}  // namespace

std::string setpoint_name_for(RigKind rig) {
  switch (rig) {
    case RigKind::kQuarterCar: return "x_ref";
    case RigKind::kPneumaticRotary: return "theta_d";
    case RigKind::kHalfCar: return "z_s_ref";  // body heave demand (0: hold the body at rest)
    case RigKind::kTwoPoster: return "x_ref";  // each post's platen demand: x_ref_1, x_ref_2
  }
  return "setpoint";
}

namespace {

// Channel i >= 1 of `channels:`: its controller and profile, built by the
// one-channel code from a copy of the config with this channel's sections,
// errors naming channels[i].
void assemble_more_channels(const RigConfig& c, const ChannelLayout& layout, AssembledRig& rig) {
  for (std::size_t i = 0; i < c.more_channels.size(); ++i) {
    RigConfig one = c;
    one.controller = c.more_channels[i].controller;
    one.profile = c.more_channels[i].profile;
    one.file = c.file + ": channels[" + std::to_string(i + 1) + "]";
    rig.more_controllers.push_back(make_controller(one, layout));
    double duration = 0.0;
    rig.more_profiles.push_back(make_profile(one, duration));
    rig.profile_duration_s = std::max(rig.profile_duration_s, duration);
    ControlChannel ch;
    ch.controller = rig.more_controllers.back().get();
    ch.profile = rig.more_profiles.back().get();
    ch.feedback_input = required_input(one, layout, "controller.feedback", one.controller.feedback);
    rig.more_channels.push_back(ch);
    rig.more_setpoint_names.push_back(setpoint_name_for(c.rig) + "_" + std::to_string(i + 2));
  }
}

}  // namespace

AssembledRig assemble_rig(const RigConfig& c) {
  AssembledRig rig;
  rig.driver = make_driver(c);
  const ChannelLayout& layout = rig.driver->layout();

  rig.controller = make_controller(c, layout);

  const int feedback = layout.input_index(c.controller.feedback);
  rig.detectors = make_detectors(c, layout, feedback);
  rig.safety = make_safety(c, feedback);
  rig.profile = make_profile(c, rig.profile_duration_s);
  rig.setpoint_name = setpoint_name_for(c.rig);
  if (c.profile.start_from_measurement) rig.profile_start_input = layout.input_index(c.controller.feedback);
  if (!c.more_channels.empty()) {
    rig.setpoint_name += "_1";
    assemble_more_channels(c, layout, rig);
  }
  return rig;
}

}  // namespace rigctl
