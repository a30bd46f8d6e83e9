#include "foxglove/telemetry/telemetry_json.hpp"

#include <nlohmann/json.hpp>

#include "rt/comms/telemetry_columns.hpp"

namespace rigctl::foxglove {

namespace {

using Json = nlohmann::ordered_json;

// A JSON Schema of a flat object, field by field, every field required.
class SchemaBuilder {
 public:
  // A number in SI units; null where the value was not a number (a NaN from
  // a failed transducer: JSON has no NaN).
  void number(const std::string& name, const std::string& unit, const std::string& what) {
    add(name, Json{{"type", Json::array({"number", "null"})}, {"description", describe(unit, what)}});
  }
  void integer(const std::string& name, const std::string& what) { add(name, Json{{"type", "integer"}, {"description", what}}); }
  void text(const std::string& name, const std::string& what) { add(name, Json{{"type", "string"}, {"description", what}}); }
  void boolean(const std::string& name, const std::string& what) { add(name, Json{{"type", "boolean"}, {"description", what}}); }
  void field(const std::string& name, Json schema) { add(name, std::move(schema)); }
  void time() { number(kTimeColumn, "s", "rig time since the start of the run"); }

  std::string build(const std::string& title, const std::string& description) const {
    return Json{{"title", title},
                {"description", description},
                {"type", "object"},
                {"properties", properties_},
                {"required", required_},
                {"additionalProperties", false}}
        .dump();
  }

 private:
  static std::string describe(const std::string& unit, const std::string& what) {
    const std::string u = unit.empty() ? "" : "[" + unit + "]";
    return what.empty() ? u : (u.empty() ? what : u + " " + what);
  }
  void add(const std::string& name, Json schema) {
    properties_[name] = std::move(schema);
    required_.push_back(name);
  }
  Json properties_ = Json::object();
  Json required_ = Json::array();
};

double seconds(int64_t ns) { return static_cast<double>(ns) * 1e-9; }
double seconds(double ns) { return ns * 1e-9; }

// --- sample -----------------------------------------------------------------

std::string json_of(const rigctl::sample_t& s) {
  Json j{{kTimeColumn, s.t}, {"tick", s.tick}, {"status", s.status}};
  const auto columns = sample_columns(s);
  for (std::size_t i = 0; i < columns.size() && i < s.values.size(); ++i) j[columns[i].name] = s.values[i];
  return j.dump();
}

std::string schema_of(const rigctl::sample_t& s) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick, 0 at the start of the run");
  b.integer("status", "bit i set: input i is invalid (stale, out of range, not a number)");
  for (const auto& c : sample_columns(s)) b.number(c.name, c.unit, "input " + c.name);
  return b.build("rigctl.Sample", "All input channels of one tick of the " + s.rig + " rig, SI units");
}

// --- command ----------------------------------------------------------------

std::string json_of(const rigctl::command_t& c) {
  Json j{{kTimeColumn, c.t}, {"tick", c.tick}};
  const auto columns = command_columns(c);
  j[columns[0].name] = c.setpoint;
  for (std::size_t i = 1; i < columns.size() && i - 1 < c.values.size(); ++i) j[columns[i].name] = c.values[i - 1];
  return j.dump();
}

std::string schema_of(const rigctl::command_t& c) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick");
  const auto columns = command_columns(c);
  b.number(columns[0].name, "", "setpoint, in the feedback input's unit");
  for (std::size_t i = 1; i < columns.size(); ++i) b.number(columns[i].name, columns[i].unit, "output written to the driver");
  return b.build("rigctl.Command", "The setpoint and the outputs written on one tick");
}

// --- controller -------------------------------------------------------------

std::string json_of(const rigctl::controller_t& k) {
  Json j{{kTimeColumn, k.t}, {"tick", k.tick}, {"controller", k.controller}, {"setpoint", k.setpoint},
         {"measurement", k.measurement}, {"error", k.error}};
  for (std::size_t i = 0; i < k.term_names.size() && i < k.terms.size(); ++i) j["term_" + k.term_names[i]] = k.terms[i];
  j["output_unsaturated"] = k.output_unsaturated;
  j["output"] = k.output;
  j["saturated"] = k.saturated != 0;  // LCM booleans are int8_t in C++
  j["integrator_held"] = k.integrator_held != 0;
  return j.dump();
}

std::string schema_of(const rigctl::controller_t& k) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick");
  b.text("controller", "controller type, e.g. pi");
  b.number("setpoint", "", "setpoint, in the feedback input's unit");
  b.number("measurement", "", "feedback input");
  b.number("error", "", "setpoint - measurement");
  for (const auto& name : k.term_names) b.number("term_" + name, "", "controller term " + name + ", in the output's unit");
  b.number("output_unsaturated", "", "output before the limit");
  b.number("output", "", "output after the limit");
  b.boolean("saturated", "output at its limit");
  b.boolean("integrator_held", "anti-windup holds the integrator");
  return b.build("rigctl.Controller", "The " + k.controller + " controller's terms on one tick");
}

// --- timing -----------------------------------------------------------------

void put_distribution(Json& j, const std::string& name, int64_t count, int64_t min, int64_t max, double mean,
                      int64_t p50, int64_t p99, int64_t p999) {
  j[name + "_count"] = count;
  j[name + "_min"] = seconds(min);
  j[name + "_max"] = seconds(max);
  j[name + "_mean"] = seconds(mean);
  j[name + "_p50"] = seconds(p50);
  j[name + "_p99"] = seconds(p99);
  j[name + "_p999"] = seconds(p999);
}

void describe_distribution(SchemaBuilder& b, const std::string& name, const std::string& what) {
  b.integer(name + "_count", what + ": ticks measured");
  for (const char* stat : {"min", "max", "mean", "p50", "p99", "p999"}) b.number(name + "_" + stat, "s", what + " " + stat);
}

std::string json_of(const rigctl::timing_t& m) {
  Json j{{kTimeColumn, seconds(m.tick * m.period_ns)}, {"tick", m.tick}, {"period", seconds(m.period_ns)},
         {"overrun_policy", m.overrun_policy}, {"queue_policy", m.queue_policy}, {"ticks", m.ticks},
         {"overruns", m.overruns}, {"missed_ticks", m.missed_ticks}, {"dropped_records", m.dropped_records}};
  put_distribution(j, "wakeup_latency", m.latency_count, m.latency_min_ns, m.latency_max_ns, m.latency_mean_ns,
                   m.latency_p50_ns, m.latency_p99_ns, m.latency_p999_ns);
  put_distribution(j, "compute", m.compute_count, m.compute_min_ns, m.compute_max_ns, m.compute_mean_ns,
                   m.compute_p50_ns, m.compute_p99_ns, m.compute_p999_ns);
  // Where the compute time goes, step by step (rt/tick_stages.hpp).
  for (std::size_t i = 0; i < m.stage_name.size(); ++i) {
    j["stage_" + m.stage_name[i] + "_max"] = i < m.stage_max_ns.size() ? seconds(m.stage_max_ns[i]) : 0.0;
    j["stage_" + m.stage_name[i] + "_mean"] = i < m.stage_mean_ns.size() ? seconds(m.stage_mean_ns[i]) : 0.0;
  }
  j["slowest_tick"] = m.slowest_tick;
  return j.dump();
}

std::string schema_of(const rigctl::timing_t& m) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick");
  b.number("period", "s", "loop period");
  b.text("overrun_policy", "skip or catch_up");
  b.text("queue_policy", "a full telemetry queue: drop (paced) or wait (simulated time)");
  b.integer("ticks", "ticks run");
  b.integer("overruns", "ticks that started late");
  b.integer("missed_ticks", "periods skipped");
  b.integer("dropped_records", "telemetry records the full queue dropped");
  describe_distribution(b, "wakeup_latency", "wake-up latency");
  describe_distribution(b, "compute", "compute time per tick");
  for (const auto& name : m.stage_name) {
    b.number("stage_" + name + "_max", "s", "the tick's " + name + " step, longest so far");
    b.number("stage_" + name + "_mean", "s", "the tick's " + name + " step, mean");
  }
  b.integer("slowest_tick", "the tick with the longest compute so far; -1: none yet");
  return b.build("rigctl.Timing", "Loop timing since the start of the run, about once a second");
}

// --- state ------------------------------------------------------------------

std::string json_of(const rigctl::state_t& st) {
  return Json{{kTimeColumn, st.t}, {"tick", st.tick}, {"state", st.state}, {"safety_state", st.safety_state},
              {"event", st.event}, {"message", st.message}}
      .dump();
}

std::string schema_of(const rigctl::state_t&) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick; -1 for a report from outside the loop");
  b.text("state", "run state: starting, running, stopping, stopped, faulted");
  b.text("safety_state", "off, hydraulics_low, hydraulics_high, armed, running, holding, stopping, faulted (SAFETY.md)");
  b.text("event", "event code, e.g. limit_tripped; empty when none");
  b.text("message", "the event for a person, naming channel and value");
  return b.build("rigctl.State", "Rig state, on every change and with every event");
}

// --- driver -----------------------------------------------------------------

std::string json_of(const rigctl::driver_status_t& d) {
  Json counters = Json::object();
  for (std::size_t i = 0; i < d.counter_names.size() && i < d.counters.size(); ++i) counters[d.counter_names[i]] = d.counters[i];
  return Json{{"driver", d.driver}, {"counters", counters}, {"events", d.events}}.dump();
}

std::string schema_of(const rigctl::driver_status_t&) {
  SchemaBuilder b;
  b.text("driver", "sim, modbus or modbus_canopen");
  b.field("counters", Json{{"type", "object"},
                           {"description", "running counters: timeouts, exceptions, reconnects, ..."},
                           {"additionalProperties", Json{{"type", "integer"}}}});
  b.field("events", Json{{"type", "array"},
                         {"description", "what failed since the previous message"},
                         {"items", Json{{"type", "string"}}}});
  return b.build("rigctl.DriverStatus", "The driver's I/O health, about once a second");
}

// --- procedure --------------------------------------------------------------

std::string json_of(const rigctl::procedure_t& p) {
  return Json{{kTimeColumn, p.t},
              {"tick", p.tick},
              {"step", p.step},
              {"step_name", p.step_name},
              {"step_kind", p.step_kind},
              {"phase", p.phase},
              {"step_cycles", p.step_cycles},
              {"total_cycles", p.total_cycles},
              {"programmed_cycles", p.programmed_cycles},
              {"ramp_in_cycles", p.ramp_in_cycles},
              {"row", p.row},
              {"row_cycles", p.row_cycles},
              {"pass", p.pass},
              {"time_left", p.time_left},
              {"wanted", p.wanted},
              {"comp_gain", p.comp_gain},
              {"comp_phase", p.comp_phase},
              {"comp_mean", p.comp_mean},
              {"comp_peak", p.comp_peak},
              {"comp_valley", p.comp_valley},
              {"amplitude_error", p.amplitude_error},
              {"phase_error", p.phase_error},
              {"peak_error", p.peak_error},
              {"valley_error", p.valley_error},
              {"peak", p.peak},
              {"valley", p.valley},
              {"pv_change", p.pv_change},
              {"damage", p.damage},
              {"stop_at_block_end", p.stop_at_block_end != 0}}
      .dump();
}

std::string schema_of(const rigctl::procedure_t&) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick");
  b.integer("step", "index into the procedure's steps");
  b.text("step_name", "the step's name: steps[i] or its name:");
  b.text("step_kind", "ramp, hold, sine, blocks, drive");
  b.text("phase", "approach, ramp_in, run, end_level, done");
  b.integer("step_cycles", "test cycles done in the step");
  b.integer("total_cycles", "test cycles done in the procedure");
  b.integer("programmed_cycles", "test cycles the procedure programs in all");
  b.integer("ramp_in_cycles", "cycles run to bring the amplitude in (not test cycles)");
  b.integer("row", "blocks: the present row");
  b.integer("row_cycles", "blocks: cycles done in the row");
  b.integer("pass", "blocks, drive: passes done");
  b.number("time_left", "s", "nominal time to the procedure's end");
  b.number("wanted", "", "the programmed demand, in the feedback input's unit");
  b.number("comp_gain", "", "amplitude_phase: command amplitude / wanted");
  b.number("comp_phase", "rad", "amplitude_phase: command phase lead");
  b.number("comp_mean", "", "amplitude_phase: command mean offset");
  b.number("comp_peak", "", "peak_valley: commanded peak of the row");
  b.number("comp_valley", "", "peak_valley: commanded valley of the row");
  b.number("amplitude_error", "", "last measured cycle: fraction of the wanted amplitude");
  b.number("phase_error", "rad", "last measured cycle");
  b.number("peak_error", "", "peak_valley: last peak's error, fraction of the wanted range");
  b.number("valley_error", "", "peak_valley: last valley's error, fraction of the wanted range");
  b.number("peak", "", "the feedback's last peak");
  b.number("valley", "", "the feedback's last valley");
  b.number("pv_change", "", "peak-valley detector: last cycle against its reference, fraction of the range");
  b.number("damage", "", "pseudo-damage of the first rainflow channel");
  b.boolean("stop_at_block_end", "an operator asked to stop at the end of the present block");
  return b.build("rigctl.Procedure", "A test procedure's step, counts, compensation and damage (docs/procedures.md)");
}

// --- channels ---------------------------------------------------------------

// Channel k (2, 3, ...: the first is command_t's and controller_t's) by its
// demand's run-file name (x_ref_2) and, suffixed with k, its fed-back input,
// output and saturation.
std::string channel_suffix(std::size_t i) { return "_" + std::to_string(i + 2); }

std::string json_of(const rigctl::channels_t& c) {
  Json j{{kTimeColumn, c.t}, {"tick", c.tick}};
  for (std::size_t i = 0; i < c.setpoint_names.size(); ++i) {
    const std::string k = channel_suffix(i);
    j[c.setpoint_names[i]] = i < c.setpoints.size() ? c.setpoints[i] : 0.0;
    j["measurement" + k] = i < c.measurements.size() ? c.measurements[i] : 0.0;
    j["output" + k] = i < c.outputs.size() ? c.outputs[i] : 0.0;
    j["saturated" + k] = i < c.saturated.size() && c.saturated[i] != 0;
  }
  return j.dump();
}

std::string schema_of(const rigctl::channels_t& c) {
  SchemaBuilder b;
  b.time();
  b.integer("tick", "loop tick");
  for (std::size_t i = 0; i < c.setpoint_names.size(); ++i) {
    const std::string k = channel_suffix(i);
    b.number(c.setpoint_names[i], "", "control channel " + k.substr(1) + "'s setpoint, in its feedback input's unit");
    b.number("measurement" + k, "", "control channel " + k.substr(1) + "'s fed-back input");
    b.number("output" + k, "", "control channel " + k.substr(1) + "'s output as commanded");
    b.boolean("saturated" + k, "control channel " + k.substr(1) + "'s output at its limit");
  }
  return b.build("rigctl.Channels", "The control channels after the first on one tick (rigs with several actuators)");
}

template <typename Msg>
std::optional<TelemetryMessage> decode_as(const uint8_t* data, std::size_t size) {
  Msg m;
  if (m.decode(data, 0, static_cast<int>(size)) < 0) return std::nullopt;
  return TelemetryMessage{std::move(m)};
}

}  // namespace

std::optional<TelemetryTopic> TelemetryTopics::topic_of(const std::string& channel) const {
  for (const auto topic : kTelemetryTopics) {
    if (channel == channel_of(topic)) return topic;
  }
  return std::nullopt;
}

const std::string& TelemetryTopics::channel_of(TelemetryTopic topic) const {
  switch (topic) {
    case TelemetryTopic::kSample: return channels_.sample;
    case TelemetryTopic::kCommand: return channels_.command;
    case TelemetryTopic::kController: return channels_.controller;
    case TelemetryTopic::kTiming: return channels_.timing;
    case TelemetryTopic::kState: return channels_.state;
    case TelemetryTopic::kDriver: return channels_.driver;
    case TelemetryTopic::kProcedure: return channels_.procedure;
    case TelemetryTopic::kChannels: return channels_.channels;
  }
  return channels_.sample;
}

std::string schema_name(TelemetryTopic topic) {
  switch (topic) {
    case TelemetryTopic::kSample: return "rigctl.Sample";
    case TelemetryTopic::kCommand: return "rigctl.Command";
    case TelemetryTopic::kController: return "rigctl.Controller";
    case TelemetryTopic::kTiming: return "rigctl.Timing";
    case TelemetryTopic::kState: return "rigctl.State";
    case TelemetryTopic::kDriver: return "rigctl.DriverStatus";
    case TelemetryTopic::kProcedure: return "rigctl.Procedure";
    case TelemetryTopic::kChannels: return "rigctl.Channels";
  }
  return "rigctl.Unknown";
}

std::optional<TelemetryMessage> decode_telemetry(TelemetryTopic topic, const uint8_t* data, std::size_t size) {
  switch (topic) {
    case TelemetryTopic::kSample: return decode_as<rigctl::sample_t>(data, size);
    case TelemetryTopic::kCommand: return decode_as<rigctl::command_t>(data, size);
    case TelemetryTopic::kController: return decode_as<rigctl::controller_t>(data, size);
    case TelemetryTopic::kTiming: return decode_as<rigctl::timing_t>(data, size);
    case TelemetryTopic::kState: return decode_as<rigctl::state_t>(data, size);
    case TelemetryTopic::kDriver: return decode_as<rigctl::driver_status_t>(data, size);
    case TelemetryTopic::kProcedure: return decode_as<rigctl::procedure_t>(data, size);
    case TelemetryTopic::kChannels: return decode_as<rigctl::channels_t>(data, size);
  }
  return std::nullopt;
}

uint64_t log_time_ns(const TelemetryMessage& message) {
  const int64_t utime = std::visit([](const auto& m) { return m.utime; }, message);
  return utime > 0 ? static_cast<uint64_t>(utime) * 1000u : 0u;
}

std::string to_json(const TelemetryMessage& message) {
  return std::visit([](const auto& m) { return json_of(m); }, message);
}

std::string json_schema(const TelemetryMessage& message) {
  return std::visit([](const auto& m) { return schema_of(m); }, message);
}

}  // namespace rigctl::foxglove
