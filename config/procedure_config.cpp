#include "config/procedure_config.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "config/config_reader.hpp"
#include "config/procedure_kinds.hpp"

namespace rigctl {

namespace {

const std::vector<std::string>& action_names() {
  static const std::vector<std::string> names{"indicate", "hold", "stop"};
  return names;
}

LimitAction action_of(const std::string& s) {
  return s == "indicate" ? LimitAction::kIndicate : s == "hold" ? LimitAction::kHold : LimitAction::kStop;
}

class StepReader {
 public:
  StepReader(const ProcedureContext& ctx, ProcedureSpec& spec) : ctx_(ctx), spec_(spec) {}

  void read_steps(ConfigReader& parent, const std::string& prefix, int depth) {
    auto items = parent.items("steps");
    if (items.empty()) parent.fail("steps", "needs at least one step");
    for (std::size_t i = 0; i < items.size(); ++i) read_step(items[i], prefix + "steps[" + std::to_string(i) + "]", depth);
  }

  int channel(ConfigReader& r, const std::string& key) {
    const std::string name = r.text(key);
    const int index = ctx_.layout->input_index(name);
    if (index < 0) {
      std::string known;
      for (const auto& c : ctx_.layout->inputs) known += (known.empty() ? "" : ", ") + c.name;
      r.fail(key, "unknown channel '" + name + "' (inputs: " + known + ")");
    }
    return index;
  }

 private:
  void read_step(ConfigReader& item, const std::string& name, int depth) {
    const auto keys = item.keys();
    if (keys.size() != 1) item.fail(keys.empty() ? "" : keys[1], "a step is one key naming its kind (" + known_kind_names<StepKind>() + ")");
    const auto kind = kind_from_string<StepKind>(keys[0]);
    if (!kind) item.fail(keys[0], unknown_kind_message<StepKind>(keys[0]));
    ConfigReader body = item.child(keys[0]);
    StepSpec s;
    s.kind = *kind;
    s.name = body.has("name") ? body.text("name") : name;
    if (s.kind == StepKind::kRepeatBegin) {
      if (depth >= kMaxRepeatDepth) item.fail(keys[0], "repeats nested deeper than " + std::to_string(kMaxRepeatDepth));
      s.repeats = body.integer("count", 1, 1'000'000'000);
      spec_.steps.push_back(s);
      read_steps(body, name + ".repeat.", depth + 1);
      StepSpec end;
      end.kind = StepKind::kRepeatEnd;
      end.name = s.name;
      spec_.steps.push_back(end);
      body.reject_unknown_keys();
      return;
    }
    if (body.has("rate")) s.rate = body.number("rate", 1e-9, 1e3);
    if (body.has("end_level")) {
      s.end_level = body.number("end_level");
      s.has_end_level = true;
    }
    switch (s.kind) {
      case StepKind::kRamp:
        s.level = body.number("level");
        if (body.has("time")) s.time_s = body.number("time", 0.0, 1e7);
        if (!(s.rate > 0.0) && !body.has("time")) s.rate = spec_.ramp_rate;
        break;
      case StepKind::kHold: s.time_s = body.number("time", 0.0, 1e9); break;
      case StepKind::kSine:
        s.rows.push_back(read_row(body));
        read_compensation(body, s, true);
        if (body.has("peak_valley_detector")) {
          auto d = body.child("peak_valley_detector");
          read_detector(d, s.peak_valley);
        }
        break;
      case StepKind::kBlocks:
        for (auto& row : body.items("rows")) {
          s.rows.push_back(read_row(row));
          row.reject_unknown_keys();
        }
        if (s.rows.empty()) body.fail("rows", "needs at least one row");
        if (s.rows.size() > 32) body.fail("rows", "at most 32 rows");
        if (body.has("repeats")) s.repeats = body.integer("repeats", 1, 1'000'000'000);
        read_compensation(body, s, false);
        break;
      case StepKind::kDrive:
        s.drive_path = body.text("file");
        s.drive_column = body.has("column") ? body.text("column") : "";
        if (body.has("repeats")) s.repeats = body.integer("repeats", 1, 1'000'000'000);
        break;
      default: break;
    }
    body.reject_unknown_keys();
    spec_.steps.push_back(s);
  }

  // One sine's level: at least 10 ticks a cycle, or the loop cannot draw it.
  BlockRow read_row(ConfigReader& r) {
    BlockRow row;
    row.mean = r.number("mean");
    row.amplitude = r.number("amplitude", 0.0);
    row.frequency_hz = r.number("frequency", 1e-6, 0.1 / ctx_.period_s);
    row.cycles = r.integer("cycles", 1, 1'000'000'000'000);
    return row;
  }

  void read_compensation(ConfigReader& r, StepSpec& s, bool sine) {
    if (!r.has("compensation")) return;
    s.compensation.kind = r.kind<Compensation>("compensation");
    if (!sine && s.compensation.kind == Compensation::kAmplitudePhase) {
      r.fail("compensation", "a block program is compensated per level: none or peak_valley");
    }
    if (r.has("compensation_gain")) s.compensation.gain = r.number("compensation_gain", 0.01, 1.0);
    if (r.has("max_correction")) s.compensation.max_factor = r.number("max_correction", 1.01, 100.0);
  }

  void read_detector(ConfigReader& r, PeakValleyDetectorSpec& d) {
    d.enabled = true;
    d.channel = r.has("channel") ? channel(r, "channel") : ctx_.feedback_input;
    d.tolerance = r.number("tolerance", 1e-6, 10.0);
    if (r.has("cycles")) d.cycles = r.integer("cycles", 1, 1'000'000);
    if (r.has("settle_cycles")) d.settle_cycles = r.integer("settle_cycles", 0, 1'000'000);
    if (r.has("reference_cycles")) d.reference_cycles = r.integer("reference_cycles", 1, 10'000);
    d.action = action_of(r.choice("action", action_names()));
    r.reject_unknown_keys();
  }

  const ProcedureContext& ctx_;
  ProcedureSpec& spec_;
};

ProcedureSpec read_procedure(ConfigReader r, const std::string& name, const std::string& hash,
                             const ProcedureContext& ctx) {
  ProcedureSpec spec;
  spec.path = name;
  spec.hash = hash;
  if (r.has("ramp_rate")) spec.ramp_rate = r.number("ramp_rate", 1e-9, 1e3);
  StepReader steps(ctx, spec);
  if (r.has("rainflow")) {
    auto rf = r.child("rainflow");
    for (const auto& ch : rf.texts("channels")) {
      const int i = ctx.layout->input_index(ch);
      if (i < 0) rf.fail("channels", "unknown channel '" + ch + "'");
      spec.rainflow_channels.push_back(i);
    }
    if (spec.rainflow_channels.size() > 4) rf.fail("channels", "at most 4 channels are counted on the tick");
    if (rf.has("basquin_exponent")) spec.basquin_exponent = rf.number("basquin_exponent", 1.0, 30.0);
    if (rf.has("reference_range")) spec.reference_range = rf.number("reference_range", 0.0);
    rf.reject_unknown_keys();
  }
  if (r.has("capture")) {
    auto c = r.child("capture");
    spec.capture.enabled = true;
    for (const auto& ch : c.has("channels") ? c.texts("channels") : std::vector<std::string>{}) {
      const int i = ctx.layout->input_index(ch);
      if (i < 0) c.fail("channels", "unknown channel '" + ch + "'");
      spec.capture.channels.push_back(i);
    }
    if (spec.capture.channels.size() > 8) c.fail("channels", "at most 8 channels");
    if (c.has("histories")) {
      const std::string h = c.text("histories");
      if (h != "log_spaced" && h != "none") c.fail("histories", "log_spaced or none, not '" + h + "'");
      spec.capture.log_spaced_histories = h == "log_spaced";
    }
    if (c.has("pre_trigger")) spec.capture.pre_trigger_s = c.number("pre_trigger", 0.0, 60.0);
    if (c.has("post_trigger")) spec.capture.post_trigger_s = c.number("post_trigger", 0.0, 60.0);
    c.reject_unknown_keys();
  }
  steps.read_steps(r, "", 0);
  r.reject_unknown_keys();
  return spec;
}

std::string fnv1a_hex(const std::string& bytes) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ConfigError(path + ": cannot read");
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

std::string text_hash(const std::string& text) { return fnv1a_hex(text); }
std::string file_hash(const std::string& path) { return fnv1a_hex(read_bytes(path)); }

ProcedureSpec load_procedure(const std::string& path, const ProcedureContext& context) {
  const std::string text = read_bytes(path);
  return read_procedure(ConfigReader::from_string(text, path), path, fnv1a_hex(text), context);
}

ProcedureSpec procedure_from_string(const std::string& text, const std::string& name, const ProcedureContext& context) {
  return read_procedure(ConfigReader::from_string(text, name), name, fnv1a_hex(text), context);
}

}  // namespace rigctl
