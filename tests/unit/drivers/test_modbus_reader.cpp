// The `modbus:` section of a rig config (config/modbus_reader): a good
// section parses to the documented SI settings, and every bad value is an
// error naming the key and the line.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "config/config_reader.hpp"
#include "config/modbus_reader.hpp"
#include "drivers/modbus/modbus_daq.hpp"

using namespace rigctl;

namespace {

const char* kGoodSection = R"(modbus:
  transport: tcp
  host: 127.0.0.1
  port: 1502
  device: /dev/ttyUSB0      # rtu keys may stay; checked, unused
  baud: 115200
  parity: N
  data_bits: 8
  stop_bits: 1
  response_timeout_s: 0.002
  reconnect_interval_s: 0.5
  max_sample_age_s: 0.0075
  max_gap: 4
  inputs:
    x_r: {unit: m, unit_id: 1, register: input, address: 0, format: int16, order: high_first, calibration: {gain: 6.1035e-6, offset: 0.0}}
    p1:  {unit: Pa, unit_id: 1, register: input, address: 5, format: float32, order: low_first, calibration: {table: {raw: [0, 1000, 2000], si: [0.0, 1.0e7, 2.05e7]}}}
    f_t: {unit: N, unit_id: 2, register: holding, address: 10, format: uint16, calibration: {gain: 0.5, offset: -1000}}
  outputs:
    u: {unit: "1", unit_id: 1, register: holding, address: 0, format: int16, order: high_first, calibration: {gain: 3.0518e-5, offset: 0.0}, safe: 0.0}
)";

ModbusDaqConfig parse(const std::string& text) {
  auto root = ConfigReader::from_string(text, "rig.yaml");
  auto c = read_modbus_daq(root.child("modbus"), 0.0025);
  root.reject_unknown_keys();
  return c;
}

// Replaces the first occurrence of `from` in text.
std::string edit(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("test edit: '" + from + "' not in the section");
  return text.replace(at, from.size(), to);
}
std::string edited(const std::string& from, const std::string& to) { return edit(kGoodSection, from, to); }

// The good section as RTU, with a timeout that fits its frames at 115200 baud.
std::string rtu_section() {
  return edit(edited("transport: tcp", "transport: rtu"), "response_timeout_s: 0.002", "response_timeout_s: 0.005");
}

std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ModbusReader, GoodSectionParses) {
  const auto c = parse(kGoodSection);
  EXPECT_EQ(c.connection.transport, ModbusTransport::kTcp);
  EXPECT_EQ(c.connection.host, "127.0.0.1");
  EXPECT_EQ(c.connection.port, 1502);
  EXPECT_DOUBLE_EQ(c.connection.response_timeout_s, 0.002);
  EXPECT_DOUBLE_EQ(c.connection.reconnect_interval_s, 0.5);
  EXPECT_DOUBLE_EQ(c.poll_period_s, 0.0025);  // the default: the loop period
  EXPECT_DOUBLE_EQ(c.max_sample_age_s, 0.0075);
  EXPECT_EQ(c.max_gap, 4);
  ASSERT_EQ(c.inputs.size(), 3u);
  EXPECT_EQ(c.inputs[0].name, "x_r");
  EXPECT_EQ(c.inputs[0].unit, "m");
  EXPECT_DOUBLE_EQ(c.inputs[0].calibration.to_si(1000), 6.1035e-3);
  EXPECT_EQ(c.inputs[1].point.format, DataFormat::kFloat32);
  EXPECT_EQ(c.inputs[1].point.order, WordOrder::kLowFirst);
  ASSERT_NE(c.inputs[1].calibration.table(), nullptr);
  EXPECT_DOUBLE_EQ(c.inputs[1].calibration.to_si(1500), 1.525e7);
  EXPECT_EQ(c.inputs[2].point.unit_id, 2);
  EXPECT_EQ(c.inputs[2].point.type, RegisterType::kHoldingRegister);
  EXPECT_EQ(c.inputs[2].point.order, WordOrder::kHighFirst);  // 16-bit default
  ASSERT_EQ(c.outputs.size(), 1u);
  EXPECT_EQ(c.outputs[0].name, "u");
  EXPECT_DOUBLE_EQ(c.outputs[0].safe, 0.0);
  EXPECT_EQ(c.io_priority, 0);  // optional: normal scheduling
  EXPECT_NO_THROW(ModbusDaq{c});
  EXPECT_EQ(parse(edited("  max_gap: 4\n", "  max_gap: 4\n  io_priority: 79\n")).io_priority, 79);

  const auto rtu = parse(rtu_section());
  EXPECT_EQ(rtu.connection.transport, ModbusTransport::kRtu);
  EXPECT_EQ(rtu.connection.device, "/dev/ttyUSB0");
  EXPECT_EQ(rtu.connection.baud, 115200);
  EXPECT_EQ(rtu.connection.parity, 'N');
  EXPECT_NO_THROW(ModbusDaq{rtu});
  // RTU without the TCP keys, with an explicit poll period.
  const auto rtu2 = parse(edit(rtu_section(), "  host: 127.0.0.1\n  port: 1502\n", "  poll_period_s: 0.005\n"));
  EXPECT_DOUBLE_EQ(rtu2.poll_period_s, 0.005);
}

struct BadCase {
  std::string name, from, to, expected;
  bool rtu = false;  // edit the RTU variant
};

TEST(ModbusReader, EachBadCaseNamesTheKey) {
  const std::vector<BadCase> cases = {
      {"missing key", "  response_timeout_s: 0.002\n", "", "rig.yaml:2: modbus.response_timeout_s: missing required key"},
      {"unknown key", "  max_gap: 4\n", "  max_gap: 4\n  retries: 3\n", "rig.yaml:14: modbus.retries: unknown key"},
      {"unknown channel key", "safe: 0.0}", "safe: 0.0, scale: 2}", "modbus.outputs.u.scale: unknown key"},
      {"bad format name", "format: int16, order: high_first, calibration: {gain: 6.1035e-6",
       "format: int17, order: high_first, calibration: {gain: 6.1035e-6",
       "rig.yaml:15: modbus.inputs.x_r.format: unknown value 'int17'"},
      {"bad order name", "order: low_first", "order: middle_endian", "modbus.inputs.p1.order: unknown value 'middle_endian'"},
      {"32-bit without order", "format: float32, order: low_first,", "format: float32,",
       "modbus.inputs.p1.order: missing required key"},
      {"bad transport", "transport: tcp", "transport: udp", "modbus.transport: unknown value 'udp'"},
      {"rtu without device", "  device: /dev/ttyUSB0      # rtu keys may stay; checked, unused\n", "",
       "modbus.device: missing required key", true},
      {"tcp without host", "  host: 127.0.0.1\n", "", "modbus.host: missing required key"},
      {"bad parity", "parity: N", "parity: X", "modbus.parity: unknown value 'X'"},
      {"bad parity, unused under tcp, still checked", "parity: N", "parity: none", "modbus.parity: unknown value 'none'"},
      {"rtu without baud", "  baud: 115200\n", "", "modbus.baud: missing required key", true},
      {"rtu broadcast unit", "unit_id: 2", "unit_id: 0", "modbus.inputs.f_t.unit_id: must be in [1, 247]", true},
      {"output in an input register", "u: {unit: \"1\", unit_id: 1, register: holding",
       "u: {unit: \"1\", unit_id: 1, register: input", "modbus.outputs.u.register: outputs must be holding registers"},
      {"output without safe", ", safe: 0.0}", "}", "modbus.outputs.u.safe: missing required key"},
      {"gain and table", "calibration: {table: {raw:", "calibration: {gain: 1, table: {raw:",
       "modbus.inputs.p1.calibration.table: give either gain and offset, or table"},
      {"table not increasing", "raw: [0, 1000, 2000]", "raw: [0, 2000, 1000]", "modbus.inputs.p1.calibration.table"},
      {"table lengths differ", "si: [0.0, 1.0e7, 2.05e7]", "si: [0.0, 1.0e7]", "modbus.inputs.p1.calibration.table.si"},
      {"zero gain", "{gain: 0.5, offset: -1000}", "{gain: 0, offset: -1000}", "modbus.inputs.f_t.calibration.gain"},
      {"address beyond the table", "address: 5, format: float32", "address: 65535, format: float32",
       "modbus.inputs.p1.address"},
      {"unit id out of range", "unit_id: 2", "unit_id: 256", "modbus.inputs.f_t.unit_id: must be in [0, 255]"},
      {"stale before the first poll", "max_sample_age_s: 0.0075", "max_sample_age_s: 0.001",
       "modbus.max_sample_age_s: must be at least the poll period"},
      {"io priority out of range", "  max_gap: 4\n", "  max_gap: 4\n  io_priority: 120\n",
       "modbus.io_priority: must be in [0, 99]"},
      {"non-numeric timeout", "response_timeout_s: 0.002", "response_timeout_s: fast",
       "modbus.response_timeout_s: expected a number"},
  };
  for (const auto& c : cases) {
    const std::string error = error_of(edit(c.rtu ? rtu_section() : kGoodSection, c.from, c.to));
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.name << ": got \"" << error << "\"";
    EXPECT_EQ(error.rfind("rig.yaml:", 0), 0u) << c.name << ": no file:line in \"" << error << "\"";
  }
}

TEST(ModbusReader, RtuTimeoutMustFitTheFramesAtTheBaudRate) {
  // At 115200 baud the 7-register read (x_r..p1) and its request take 27
  // bytes, 2.3 ms: a 2 ms timeout would fail every time.
  const std::string tight = edited("transport: tcp", "transport: rtu");
  const std::string e = error_of(tight);
  EXPECT_NE(e.find("rig.yaml:10: modbus.response_timeout_s: 0.002 s is shorter than the 27 bytes"), std::string::npos) << e;
  EXPECT_EQ(error_of(rtu_section()), "(no error)");
  const std::string slow = edit(rtu_section(), "baud: 115200", "baud: 9600");
  EXPECT_NE(error_of(slow).find("modbus.response_timeout_s"), std::string::npos) << error_of(slow);
  // The same section over TCP has no such limit.
  EXPECT_EQ(error_of(kGoodSection), "(no error)");
}

TEST(ModbusReader, OverlappingOutputsAreRejected) {
  std::string s = kGoodSection;
  s += "    v: {unit: \"1\", unit_id: 1, register: holding, address: 0, format: uint16, "
       "calibration: {gain: 1, offset: 0}, safe: 0}\n";
  EXPECT_NE(error_of(s).find("modbus.outputs.v: shares registers with output u"), std::string::npos) << error_of(s);
}

}  // namespace
