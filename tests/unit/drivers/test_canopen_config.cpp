// The `canopen:` config section (config/canopen_reader.hpp): the example
// with its defaults, and errors that name file, line and key.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "config/canopen_reader.hpp"
#include "drivers/canopen/canopen_valve.hpp"

using namespace rigctl;


namespace {
const char* kCanopenYaml = R"(canopen:
  socket_path: /run/rigctl/valve.sock
  node_id: 1
  heartbeat_timeout_s: 0.05
  heartbeat_period_s: 0.02
  sdo_timeout_s: 0.1
  actual_max_age_s: 0.0075
  setpoint_output: u
  actual_input: x_s
  startup_sdo:
    device_mode: {index: 0x6042, subindex: 0, size: 1, value: 1}
    control_word: {index: 0x6040, subindex: 0, size: 2, value: 0x0007}
)";

CanopenValveConfig parse(const std::string& yaml) {
  return read_canopen_valve(ConfigReader::from_string(yaml, "test.yaml").child("canopen"));
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

void expect_error(const std::string& yaml, const std::vector<std::string>& fragments) {
  const std::string e = error_of(yaml);
  ASSERT_FALSE(e.empty()) << "config was accepted";
  for (const auto& f : fragments) EXPECT_NE(e.find(f), std::string::npos) << "'" << f << "' not in: " << e;
}
}  // namespace

TEST(CanopenConfig, ExampleParsesWithDefaults) {
  const CanopenValveConfig c = parse(kCanopenYaml);
  EXPECT_EQ(c.socket_path, "/run/rigctl/valve.sock");
  EXPECT_TRUE(c.interface.empty());
  EXPECT_EQ(c.node_id, 1);
  EXPECT_EQ(c.master_node_id, 127);
  EXPECT_DOUBLE_EQ(c.heartbeat_timeout_s, 0.05);
  EXPECT_DOUBLE_EQ(c.valve_heartbeat_period_s, 0.016);  // timeout / 3, whole ms
  EXPECT_DOUBLE_EQ(c.valve_consumer_time_s, 0.05);      // 2.5 x our period
  EXPECT_TRUE(c.reset_on_start);
  EXPECT_TRUE(c.configure_heartbeats);
  ASSERT_EQ(c.startup_sdo.size(), 2U);
  EXPECT_EQ(c.startup_sdo[0].name, "device_mode");
  EXPECT_EQ(c.startup_sdo[0].index, 0x6042);
  EXPECT_EQ(c.startup_sdo[0].size, 1);
  EXPECT_EQ(c.startup_sdo[0].value, 1U);
  EXPECT_EQ(c.startup_sdo[1].index, 0x6040);
  EXPECT_EQ(c.startup_sdo[1].value, 7U);
  EXPECT_EQ(c.actual_input, "x_s");
  EXPECT_TRUE(c.pressure_input.empty());
  EXPECT_NO_THROW(CanopenValve v(c));

  const CanopenValveConfig can = parse(replace(kCanopenYaml, "socket_path: /run/rigctl/valve.sock", "interface: can0"));
  EXPECT_EQ(can.interface, "can0");
  EXPECT_TRUE(can.socket_path.empty());
}

TEST(CanopenConfig, NegativeValueIsStoredAsTwosComplementOfItsSize) {
  const auto c = parse(replace(kCanopenYaml, "value: 0x0007", "value: -2"));
  EXPECT_EQ(c.startup_sdo[1].value, 0xFFFEU);
}

TEST(CanopenConfig, ErrorsNameFileLineAndKey) {
  expect_error(replace(kCanopenYaml, "  node_id: 1\n", "  node_id: 1\n  interface: can0\n"),
               {"test.yaml:2:", "canopen.socket_path", "not both"});
  expect_error(replace(kCanopenYaml, "  socket_path: /run/rigctl/valve.sock\n", ""), {"test.yaml:", "canopen.interface", "missing"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 128"), {"test.yaml:3:", "canopen.node_id", "128"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 1\n  colour: red"), {"test.yaml:4:", "canopen.colour", "unknown key"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 1, value: 1, mode: rw}"),
               {"test.yaml:11:", "canopen.startup_sdo.device_mode.mode", "unknown key"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 1, value: 300}"),
               {"test.yaml:11:", "canopen.startup_sdo.device_mode.value", "must be in [-128, 255]"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 5, value: 1}"), {"canopen.startup_sdo.device_mode.size"});
  expect_error(replace(kCanopenYaml, "index: 0x6040", "index: 0x10000"), {"canopen.startup_sdo.control_word.index"});
  expect_error(replace(replace(kCanopenYaml, "    device_mode: {", "    - {"), "    control_word: {", "    - {"),
               {"canopen.startup_sdo", "expected a mapping", "named entry"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_heartbeat_period_s: 0.0105"),
               {"canopen.valve_heartbeat_period_s", "whole number of milliseconds"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_heartbeat_period_s: 0.06"),
               {"canopen.valve_heartbeat_period_s", "shorter than heartbeat_timeout_s"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_consumer_time_s: 0.02"),
               {"canopen.valve_consumer_time_s", "longer than our heartbeat_period_s"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 1\n  master_node_id: 1"), {"canopen.master_node_id", "differ"});
  expect_error(replace(kCanopenYaml, "actual_input: x_s", "actual_input: x_s\n  pressure_scale_pa: 1000"),
               {"canopen.pressure_scale_pa", "pressure_input"});
  expect_error(replace(kCanopenYaml, "actual_input: x_s", "actual_input: x_s\n  pressure_input: p_v"),
               {"canopen.pressure_scale_pa", "missing"});
  expect_error(replace(kCanopenYaml, "sdo_timeout_s: 0.1", "sdo_timeout_s: soon"), {"canopen.sdo_timeout_s", "expected a number"});
}

TEST(CanopenConfig, StartUpAndPdoSettingsHaveTheirDefaultsAndAreRead) {
  const CanopenValveConfig d = parse(kCanopenYaml);
  EXPECT_DOUBLE_EQ(d.boot_timeout_s, 1.0);
  EXPECT_DOUBLE_EQ(d.device_state_timeout_s, 0.5);
  EXPECT_TRUE(d.configure_pdos);
  EXPECT_DOUBLE_EQ(d.actual_period_s, 0.001);
  EXPECT_DOUBLE_EQ(d.setpoint_timeout_s, 0.05);
  EXPECT_EQ(d.spool_full_scale, 0);  // the valve's 0x6311:1

  const CanopenValveConfig c = parse(replace(kCanopenYaml, "actual_max_age_s: 0.0075",
                                             "actual_max_age_s: 0.0075\n  boot_timeout_s: 0.2\n"
                                             "  device_state_timeout_s: 0.1\n  configure_pdos: false\n"
                                             "  actual_period_s: 0.002\n  setpoint_timeout_s: 0\n  spool_full_scale: 8192"));
  EXPECT_DOUBLE_EQ(c.boot_timeout_s, 0.2);
  EXPECT_DOUBLE_EQ(c.device_state_timeout_s, 0.1);
  EXPECT_FALSE(c.configure_pdos);
  EXPECT_DOUBLE_EQ(c.actual_period_s, 0.002);
  EXPECT_DOUBLE_EQ(c.setpoint_timeout_s, 0.0);
  EXPECT_EQ(c.spool_full_scale, 8192);
  EXPECT_NO_THROW(CanopenValve v(c));
}

TEST(CanopenConfig, PdoSettingsThatCannotWorkAreErrors) {
  const std::string base = kCanopenYaml;
  expect_error(replace(base, "actual_max_age_s: 0.0075", "actual_max_age_s: 0.0075\n  actual_period_s: 0.008"),
               {"test.yaml:", "canopen.actual_period_s", "shorter than actual_max_age_s"});
  expect_error(replace(base, "actual_max_age_s: 0.0075", "actual_max_age_s: 0.0075\n  actual_period_s: 0.0015"),
               {"canopen.actual_period_s", "whole number of milliseconds"});
  expect_error(replace(base, "actual_max_age_s: 0.0075", "actual_max_age_s: 0.0075\n  setpoint_timeout_s: 0.002"),
               {"canopen.setpoint_timeout_s", "at least 0.004"});
  expect_error(replace(base, "actual_max_age_s: 0.0075", "actual_max_age_s: 0.0075\n  spool_full_scale: 0"),
               {"canopen.spool_full_scale", "must be in [1, 32767]"});
  expect_error(replace(base, "actual_max_age_s: 0.0075", "actual_max_age_s: 0.0075\n  configure_pdos: maybe"),
               {"canopen.configure_pdos"});
}
