#include "config/rig_config.hpp"
#include "config/suspension_controller_reader.hpp"

#include <arpa/inet.h>

#include <filesystem>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "config/canopen_reader.hpp"
#include "config/modbus_reader.hpp"
#include "config/plant_readers.hpp"

namespace rigctl {

// config/safety_config.cpp
SafetyConfig read_safety(ConfigReader r);

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

WebsocketConfig read_websocket(ConfigReader r) {
  WebsocketConfig c;
  if (r.has("address")) {
    c.address = r.text("address");
    in6_addr any{};
    if (inet_pton(AF_INET, c.address.c_str(), &any) != 1 && inet_pton(AF_INET6, c.address.c_str(), &any) != 1) {
      r.fail("address", "'" + c.address + "' is not an IPv4 or IPv6 address (e.g. 127.0.0.1, 0.0.0.0)");
    }
  }
  c.port = static_cast<int>(r.integer("port", 0, 65535));
  if (r.has("client_queue")) c.client_queue_messages = static_cast<int>(r.integer("client_queue", 1, 1'000'000));
  if (r.has("max_clients")) c.max_clients = static_cast<int>(r.integer("max_clients", 1, 256));
  if (r.has("allowed_origins")) {
    c.allowed_origins = r.texts("allowed_origins", [](const std::string& o) {
      const auto scheme = o.find("://");
      const std::string s = scheme == std::string::npos ? "" : o.substr(0, scheme);
      const std::string host = scheme == std::string::npos ? "" : o.substr(scheme + 3);
      if ((s != "http" && s != "https") || host.empty() || host.find_first_of("/?#@ ") != std::string::npos) {
        throw std::invalid_argument("'" + o + "' is not an origin: scheme://host[:port], no path (e.g. https://rig1.lab.example)");
      }
    });
  }
  if (r.has("control_timeout_s")) c.control_timeout_s = r.number("control_timeout_s", 0.1, 60.0);
  if (r.has("client_timeout_s")) c.client_timeout_s = r.number("client_timeout_s", 0.5, 3600.0);
  r.reject_unknown_keys();
  return c;
}

TelemetryConfig read_telemetry(ConfigReader r) {
  TelemetryConfig c;
  c.lcm_url = r.text("lcm_url");
  if (c.lcm_url.find("://") == std::string::npos) r.fail("lcm_url", "expected a URL such as memq:// or udpm://ADDR:PORT?ttl=0");
  c.channel_prefix = r.text("channel_prefix");
  c.log_dir = r.text("log_dir");
  if (r.has("websocket")) c.websocket = read_websocket(r.child("websocket"));
  r.reject_unknown_keys();
  return c;
}

CatalogConfig read_catalog(ConfigReader r) {
  CatalogConfig c;
  c.path = r.text("path");
  if (c.path.empty()) r.fail("path", "expected the catalog's file, e.g. runs/catalog.sqlite");
  if (r.has("rig_name")) c.rig_name = r.text("rig_name");
  r.reject_unknown_keys();
  return c;
}

PiConfig read_pi(ConfigReader& r, double period_s) {
  PiConfig pi;
  pi.kp = r.number("kp", 0.0, 1e6);
  pi.ki = r.number("ki", 0.0, 1e6);
  // Optional: a tuned config has it (`rigctl tune`); 1e3 s/m would open the
  // valve fully for 1 mm/s, beyond any rig.
  if (r.has("velocity_feedforward")) pi.velocity_feedforward = r.number("velocity_feedforward", 0.0, 1e3);
  pi.output_limit = r.number("output_limit", 1e-6, 1e6);
  pi.anti_windup = r.choice("anti_windup", {"conditional", "none"}) == "none" ? AntiWindup::kNone
                                                                            : AntiWindup::kConditional;
  pi.period_s = period_s;
  return pi;
}

PvpConfig read_pvp(ConfigReader& r, double period_s) {
  PvpConfig pvp;
  pvp.ke = r.number("ke", 0.0, 1e4);
  pvp.kv = r.number("kv", 0.0, 1e4);
  pvp.kp = r.number("kp_v_per_bar", 0.0, 1e3) / 1e5;  // the paper's V/bar, to V/Pa
  pvp.transient_pressure = r.boolean("transient_pressure");
  pvp.tau_f = r.number("transient_tau_s", 1e-3, 1e3);
  pvp.velocity_filter_tau = r.number("velocity_filter_tau_s", 0.0, 10.0);
  pvp.output_limit = r.number("output_limit", 1e-6, 1e6);
  pvp.period_s = period_s;
  return pvp;
}

ControllerConfig read_controller(ConfigReader r, RigKind rig, double period_s) {
  ControllerConfig c;
  // Each rig has the controller of its paper (the half car also the baselines).
  c.type = read_controller_kind(r, "type", rig);
  switch (c.type) {
    case ControllerKind::kPi:
      c.feedback = r.text("feedback");
      c.output = r.text("output");
      c.pi = read_pi(r, period_s);
      break;
    case ControllerKind::kPvp:
      c.feedback = r.text("feedback");
      c.output = r.text("output");
      c.pressure = r.text("pressure");
      c.pvp = read_pvp(r, period_s);
      break;
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr:
      // Every controller's settings are required: `rigctl compare` runs them all.
      c.feedback = r.choice("feedback", {"z_s"});  // the regulated body heave (the other body states by their run-file names)
      read_suspension_controller(r, c.suspension);
      c.output = c.suspension.output_1;
      break;
  }
  r.reject_unknown_keys();
  return c;
}

// The lead-in of ramp_steps and sine: hold at the start, then ramp to ramp_target.
void read_lead_in(ConfigReader& r, ProfileConfig& c) {
  // `start: measured` begins the lead-in where the feedback stands, so a
  // run never starts with a jump in demand (the physical rig's choice).
  if (r.has("start") && r.text("start") == "measured") {
    c.start_from_measurement = true;
  } else {
    c.start = r.number("start", -10.0, 10.0);
  }
  c.hold_s = r.number("hold_s", 0.0, 1e5);
  c.ramp_target = r.number("ramp_target", -10.0, 10.0);
  c.ramp_rate = r.number("ramp_rate", 1e-6, 100.0);
}

ProfileConfig read_profile(ConfigReader r, const std::string& config_file) {
  ProfileConfig c;
  c.type = r.kind<ProfileKind>("type");
  c.filter_tau_s = r.number("filter_tau_s", 0.0, 100.0);
  switch (c.type) {
    case ProfileKind::kHold:
      // A constant demand (a regulator: the half car holds its body at rest
      // while the road moves under it).
      c.value = r.number("value", -10.0, 10.0);
      c.duration_s = r.number("duration_s", 1e-3, 1e7);
      break;
    case ProfileKind::kCsv: {
      const std::filesystem::path file = r.text("file");
      c.csv_file = file.is_absolute() ? file.string()
                                      : (std::filesystem::path(config_file).parent_path() / file).string();
      c.csv_column = r.text("column");
      break;
    }
    case ProfileKind::kRampSteps:
      read_lead_in(r, c);
      c.steps = r.numbers("steps", 1, 10000, -10.0, 10.0);
      c.step_hold_s = r.number("step_hold_s", 1e-3, 1e5);
      break;
    case ProfileKind::kSine:
      read_lead_in(r, c);
      c.amplitude = r.number("amplitude", 0.0, 10.0);
      c.frequency_hz = r.number("frequency_hz", 1e-4, 1e3);
      c.cycles = r.number("cycles", 0.0, 1e7);
      break;
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

// Sensors have noise and offset; output converters (DACs) only bits and range.
std::map<std::string, SensorSpec> read_converters(ConfigReader r, bool sensor) {
  std::map<std::string, SensorSpec> out;
  for (const auto& channel : r.keys()) {
    auto s = r.child(channel);
    SensorSpec spec;
    if (sensor) spec.noise_sd = s.number("noise_sd", 0.0, kInf);
    spec.bits = static_cast<int>(s.integer("bits", 0, 32));
    const auto range = s.numbers("range", 2, 2);
    if (!(range[0] < range[1])) s.fail("range", "must be [min, max] with min < max");
    spec.range_min = range[0];
    spec.range_max = range[1];
    if (sensor) spec.offset = s.number("offset");
    s.reject_unknown_keys();
    out[channel] = spec;
  }
  return out;
}

// One control channel (`controller:` and `profile:`), or several: a
// `channels:` list with one {controller, profile} per actuator, the first of
// which is the rig's first channel.
void read_channels(ConfigReader& root, RigConfig& c) {
  if (!root.has("channels")) {
    c.controller = read_controller(root.child("controller"), c.rig, c.loop.period_s);
    c.profile = read_profile(root.child("profile"), c.file);
    return;
  }
  for (const char* single : {"controller", "profile"}) {
    if (root.has(single)) root.fail(single, "give either `channels:` or `controller:` and `profile:`, not both");
  }
  auto items = root.items("channels");
  if (items.empty()) root.fail("channels", "expected at least one channel");
  if (items.size() > kMaxChannels) {
    root.fail("channels", std::to_string(items.size()) + " channels, at most " + std::to_string(kMaxChannels));
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    ChannelConfig ch;
    ch.controller = read_controller(items[i].child("controller"), c.rig, c.loop.period_s);
    ch.profile = read_profile(items[i].child("profile"), c.file);
    items[i].reject_unknown_keys();
    if (i == 0) {
      c.controller = ch.controller;
      c.profile = ch.profile;
    } else {
      c.more_channels.push_back(ch);
    }
  }
}

RigConfig parse(ConfigReader root, const std::string& case_name) {
  RigConfig c;
  c.file = root.file();
  c.case_name = case_name;
  c.rig = root.kind<RigKind>("rig");
  c.driver = root.kind<DriverKind>("driver");
  c.seed = static_cast<uint64_t>(root.integer("seed", 0, std::numeric_limits<int64_t>::max()));
  c.loop = read_loop(root.child("loop"));
  c.telemetry = read_telemetry(root.child("telemetry"));
  read_channels(root, c);
  if (root.has("limits")) c.limits = read_limits(root.child("limits"));
  if (root.has("safety")) c.safety = read_safety(root.child("safety"));
  if (root.has("operator")) c.operator_commands = read_operator(root.child("operator"), c.file);
  if (root.has("identify")) c.identify = read_identify(root.child("identify"));
  if (root.has("catalog")) c.catalog = read_catalog(root.child("catalog"));
  if (root.has("faults")) {
    for (const auto& text : root.texts("faults", [](const std::string& t) { parse_fault_spec(t); })) {
      c.faults.push_back(parse_fault_spec(text));
    }
  }
  switch (c.rig) {
    case RigKind::kQuarterCar:
      read_quarter_car_plant(root.child("plant"), c.quarter_car);
      break;
    case RigKind::kPneumaticRotary:
      read_pneumatic_rotary_plant(root.child("plant"), c.pneumatic_rotary);
      break;
    case RigKind::kHalfCar:
      read_half_car_plant(root.child("plant"), c.half_car);
      c.suspension_report = read_suspension_report(root.child("report"));
      c.suspension_optimize = read_suspension_optimize(root.child("optimize"));
      break;
    case RigKind::kTwoPoster:
      read_two_poster_plant(root.child("plant"), c.two_poster);
      break;
  }
  c.sensors = read_converters(root.child("sensors"), true);
  c.dacs = read_converters(root.child("outputs"), false);
  if (root.has("modbus") || uses_modbus_daq(c.driver)) c.modbus = read_modbus_daq(root.child("modbus"), c.loop.period_s);
  if (root.has("canopen") || uses_canopen_valve(c.driver)) c.canopen = read_canopen_valve(root.child("canopen"));
  if (root.has("driver_start_timeout_s")) c.driver_start_timeout_s = root.number("driver_start_timeout_s", 0.01, 60.0);
  root.reject_unknown_keys();
  return c;
}

}  // namespace

RigConfig load_rig_config(const std::string& path, const std::string& case_name) {
  return parse(ConfigReader::load(path, case_name), case_name);
}

RigConfig parse_rig_config(const std::string& yaml_text, const std::string& name, const std::string& case_name) {
  return parse(ConfigReader::from_string(yaml_text, name, case_name), case_name);
}

std::vector<std::string> config_case_names(const std::string& path) { return ConfigReader::case_names(path); }

}  // namespace rigctl
