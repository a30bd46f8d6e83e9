#include "config/canopen_reader.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace rigctl {

namespace {

// A time the valve stores in whole milliseconds (UNSIGNED16 ms).
double valve_milliseconds(ConfigReader& r, const std::string& key) {
  const double s = r.number(key, 0.001, 65.535);
  if (std::fabs(s * 1000.0 - std::round(s * 1000.0)) > 1e-6) r.fail(key, "must be a whole number of milliseconds");
  return s;
}

std::vector<SdoWrite> read_startup_sdo(ConfigReader& parent) {
  ConfigReader list = [&] {
    try {
      return parent.child("startup_sdo");
    } catch (const ConfigError& e) {
      throw ConfigError(std::string(e.what()) +
                        " (write each start-up SDO write as a named entry, e.g. "
                        "device_mode: {index: 0x6042, subindex: 0, size: 1, value: 1})");
    }
  }();
  std::vector<SdoWrite> writes;
  for (const auto& name : list.keys()) {
    ConfigReader w = list.child(name);
    SdoWrite s;
    s.name = name;
    s.index = static_cast<uint16_t>(w.integer("index", 0x1000, 0xFFFF));
    s.subindex = static_cast<uint8_t>(w.integer("subindex", 0, 255));
    s.size = static_cast<uint8_t>(w.integer("size", 1, 4));
    const int bits = 8 * s.size;
    // Signed or unsigned, as long as it fits the object's size.
    const int64_t value = w.integer("value", -(int64_t{1} << (bits - 1)), (int64_t{1} << bits) - 1);
    s.value = static_cast<uint32_t>(value) & static_cast<uint32_t>((uint64_t{1} << bits) - 1);
    w.reject_unknown_keys();
    writes.push_back(s);
  }
  list.reject_unknown_keys();
  return writes;
}

// The PDOs the client sets up in the valve, and the spool scale.
void read_pdo_settings(ConfigReader& r, CanopenValveConfig& c) {
  if (r.has("configure_pdos")) c.configure_pdos = r.boolean("configure_pdos");
  if (r.has("actual_period_s")) c.actual_period_s = valve_milliseconds(r, "actual_period_s");
  if (c.actual_period_s >= c.actual_max_age_s) {
    r.fail(r.has("actual_period_s") ? "actual_period_s" : "actual_max_age_s",
           "the valve's actual value period must be shorter than actual_max_age_s");
  }
  if (r.has("setpoint_timeout_s")) {
    c.setpoint_timeout_s = r.number("setpoint_timeout_s", 0.0, 65.535);
    if (c.setpoint_timeout_s != 0.0) {
      c.setpoint_timeout_s = valve_milliseconds(r, "setpoint_timeout_s");
      if (c.setpoint_timeout_s < 0.004) r.fail("setpoint_timeout_s", "must be 0 (off) or at least 0.004 s");
    }
  }
  if (r.has("spool_full_scale")) c.spool_full_scale = static_cast<int>(r.integer("spool_full_scale", 1, 32767));
}

}  // namespace

CanopenValveConfig read_canopen_valve(ConfigReader r) {
  CanopenValveConfig c;
  const bool has_interface = r.has("interface");
  const bool has_path = r.has("socket_path");
  if (has_interface && has_path) r.fail("socket_path", "give either interface (SocketCAN) or socket_path, not both");
  if (!has_interface && !has_path) {
    r.fail("interface", "missing: give interface (a SocketCAN interface such as can0) or socket_path (a seqpacket socket)");
  }
  if (has_interface) {
    c.interface = r.text("interface");
    if (c.interface.empty() || c.interface.size() > 15) r.fail("interface", "must be an interface name of 1 to 15 characters");
  } else {
    c.socket_path = r.text("socket_path");
    if (c.socket_path.empty() || c.socket_path.size() > 107) r.fail("socket_path", "must be a path of 1 to 107 characters");
  }

  c.node_id = static_cast<uint8_t>(r.integer("node_id", 1, 127));
  if (r.has("master_node_id")) {
    c.master_node_id = static_cast<uint8_t>(r.integer("master_node_id", 1, 127));
    if (c.master_node_id == c.node_id) r.fail("master_node_id", "must differ from node_id");
  } else if (c.node_id == c.master_node_id) {
    r.fail("node_id", "127 is the default master_node_id; set master_node_id to another id");
  }

  c.heartbeat_timeout_s = r.number("heartbeat_timeout_s", 0.001, 60.0);
  c.heartbeat_period_s = r.number("heartbeat_period_s", 0.001, 60.0);
  if (r.has("configure_heartbeats")) c.configure_heartbeats = r.boolean("configure_heartbeats");
  if (r.has("valve_heartbeat_period_s")) {
    c.valve_heartbeat_period_s = valve_milliseconds(r, "valve_heartbeat_period_s");
  } else {
    c.valve_heartbeat_period_s = std::max(1.0, std::floor(c.heartbeat_timeout_s * 1000.0 / 3.0)) / 1000.0;
  }
  if (r.has("valve_consumer_time_s")) {
    c.valve_consumer_time_s = valve_milliseconds(r, "valve_consumer_time_s");
  } else {
    c.valve_consumer_time_s = std::min(65.535, std::ceil(c.heartbeat_period_s * 2500.0) / 1000.0);
  }
  if (c.configure_heartbeats) {
    if (c.valve_heartbeat_period_s >= c.heartbeat_timeout_s) {
      r.fail(r.has("valve_heartbeat_period_s") ? "valve_heartbeat_period_s" : "heartbeat_timeout_s",
             "the valve's heartbeat period must be shorter than heartbeat_timeout_s");
    }
    if (c.valve_consumer_time_s <= c.heartbeat_period_s) {
      r.fail(r.has("valve_consumer_time_s") ? "valve_consumer_time_s" : "heartbeat_period_s",
             "the valve's consumer time must be longer than our heartbeat_period_s");
    }
  }
  if (r.has("reset_on_start")) c.reset_on_start = r.boolean("reset_on_start");
  if (r.has("boot_timeout_s")) c.boot_timeout_s = r.number("boot_timeout_s", 0.001, 600.0);

  c.sdo_timeout_s = r.number("sdo_timeout_s", 0.001, 10.0);
  if (r.has("io_priority")) c.io_priority = static_cast<int>(r.integer("io_priority", 0, 99));
  if (r.has("startup_timeout_s")) c.startup_timeout_s = r.number("startup_timeout_s", 0.01, 600.0);
  if (r.has("device_state_timeout_s")) c.device_state_timeout_s = r.number("device_state_timeout_s", 0.001, 600.0);
  c.actual_max_age_s = r.number("actual_max_age_s", 1e-6, 10.0);
  read_pdo_settings(r, c);

  c.setpoint_output = r.text("setpoint_output");
  if (c.setpoint_output.empty()) r.fail("setpoint_output", "must name an output channel");
  c.actual_input = r.text("actual_input");
  if (c.actual_input.empty()) r.fail("actual_input", "must name an input channel");
  if (r.has("pressure_input")) {
    c.pressure_input = r.text("pressure_input");
    if (c.pressure_input.empty() || c.pressure_input == c.actual_input) {
      r.fail("pressure_input", "must name an input channel other than actual_input");
    }
    c.pressure_scale_pa = r.number("pressure_scale_pa", 1e-9, 1e9);
  } else if (r.has("pressure_scale_pa")) {
    r.fail("pressure_scale_pa", "only meaningful with pressure_input");
  }
  if (r.has("setpoint_rpdo")) c.setpoint_rpdo = static_cast<int>(r.integer("setpoint_rpdo", 1, 4));
  if (r.has("actual_tpdo")) c.actual_tpdo = static_cast<int>(r.integer("actual_tpdo", 1, 4));
  if (r.has("startup_sdo")) c.startup_sdo = read_startup_sdo(r);
  r.reject_unknown_keys();
  return c;
}

}  // namespace rigctl
