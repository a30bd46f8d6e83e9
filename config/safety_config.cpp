// Reader of the `safety:` section (struct SafetyConfig in config/rig_config.hpp).
#include "config/config_reader.hpp"
#include "config/rig_config.hpp"

namespace rigctl {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<std::string>& action_names() {
  static const std::vector<std::string> names{"indicate", "hold", "stop", "interlock"};
  return names;
}

DetectorConfig read_detector(ConfigReader r, const std::string& name) {
  DetectorConfig d;
  d.name = name;
  d.type = r.kind<DetectorKind>("type");
  d.action = limit_action_from_string(r.choice("action", action_names()));
  if (r.has("latch")) d.latch = r.boolean("latch");
  auto range = [&](const char* key) {
    const auto v = r.numbers(key, 2, 2);
    if (!(v[0] < v[1])) r.fail(key, "must be [min, max] with min < max");
    d.min = v[0];
    d.max = v[1];
  };
  // Persistence (debounce) for the kinds without a defining duration.
  auto debounce = [&] {
    if (r.has("duration_s")) d.duration_s = r.number("duration_s", 0.0, 3600.0);
  };
  switch (d.type) {
    case DetectorKind::kRange:
      d.channel = r.text("channel");
      range("range");
      debounce();
      break;
    case DetectorKind::kOpenCircuit:
      d.channel = r.text("channel");
      range("rails");
      debounce();
      break;
    case DetectorKind::kRate:
      d.channel = r.text("channel");
      d.max = r.number("max", 0.0, kInf);
      debounce();
      break;
    case DetectorKind::kTrackingError:
      if (r.has("channel")) d.channel = r.text("channel");
      d.max = r.number("max", 0.0, kInf);
      debounce();
      break;
    case DetectorKind::kValveSaturation:
      d.output = r.text("output");
      d.max = r.number("level", 0.0, kInf);
      d.duration_s = r.number("duration_s", 0.0, 3600.0);
      break;
    case DetectorKind::kSampleAge:
      d.max = r.number("max_s", 0.0, 3600.0);
      debounce();
      break;
    case DetectorKind::kOverruns:
      d.max_count = r.integer("max_count", 0, 1'000'000);
      d.window_s = r.number("window_s", 1e-3, 3600.0);
      debounce();
      break;
    case DetectorKind::kStuck:
      d.channel = r.text("channel");
      d.output = r.text("output");
      d.tolerance = r.number("tolerance", 0.0, kInf);
      d.command_min = r.number("command_min", 0.0, kInf);
      d.duration_s = r.number("duration_s", 1e-3, 3600.0);
      break;
    case DetectorKind::kInvalid:
      // Not a configurable kind (KindNames<DetectorKind>::known): r.kind never returns it.
      r.fail("type", "'invalid' is built for every input, not configured");
  }
  r.reject_unknown_keys();
  return d;
}

}  // namespace

LimitAction limit_action_from_string(const std::string& s) {
  if (s == "indicate") return LimitAction::kIndicate;
  if (s == "hold") return LimitAction::kHold;
  if (s == "stop") return LimitAction::kStop;
  return LimitAction::kInterlock;
}

SafetyConfig read_safety(ConfigReader r) {
  SafetyConfig c;
  c.auto_sequence = r.boolean("auto_sequence");
  auto h = r.child("hydraulics");
  c.low_settle_s = h.number("low_settle_s", 0.0, 600.0);
  c.high_settle_s = h.number("high_settle_s", 0.0, 600.0);
  h.reject_unknown_keys();
  c.hold_deceleration = r.number("hold_deceleration", 1e-6, kInf);
  c.setpoint_rate = r.number("setpoint_rate", 1e-9, kInf);
  if (r.has("setpoint_range")) {
    const auto v = r.numbers("setpoint_range", 2, 2);
    if (!(v[0] < v[1])) r.fail("setpoint_range", "must be [min, max] with min < max");
    c.setpoint_min = v[0];
    c.setpoint_max = v[1];
  }
  c.stop_timeout_s = r.number("stop_timeout_s", 0.01, 600.0);
  c.limits_action = limit_action_from_string(r.choice("limits_action", action_names()));
  if (r.has("detectors")) {
    auto d = r.child("detectors");
    for (const auto& name : d.keys()) c.detectors.push_back(read_detector(d.child(name), name));
    d.reject_unknown_keys();
  }
  r.reject_unknown_keys();
  return c;
}

}  // namespace rigctl
