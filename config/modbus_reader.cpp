#include "config/modbus_reader.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/modbus/modbus_write_plan.hpp"
#include "rt/sample.hpp"

namespace rigctl {

namespace {

std::vector<std::string> names(std::span<const std::string_view> list) {
  return {list.begin(), list.end()};
}

Calibration read_calibration(ConfigReader r) {
  if (r.has("table")) {
    if (r.has("gain") || r.has("offset")) r.fail("table", "give either gain and offset, or table, not both");
    auto t = r.child("table");
    const auto raw = t.numbers("raw", 2, 10000);
    const auto si = t.numbers("si", 2, 10000);
    if (raw.size() != si.size()) {
      t.fail("si", "needs one value per raw value (" + std::to_string(raw.size()) + "), got " + std::to_string(si.size()));
    }
    t.reject_unknown_keys();
    r.reject_unknown_keys();
    try {
      return TableCalibration(raw, si);
    } catch (const std::invalid_argument& e) {
      r.fail("table", e.what());
    }
  }
  const double gain = r.number("gain");
  const double offset = r.number("offset");
  r.reject_unknown_keys();
  try {
    return LinearCalibration(gain, offset);
  } catch (const std::invalid_argument& e) {
    r.fail("gain", e.what());
  }
}

ModbusChannel read_channel(ConfigReader r, const std::string& name, bool output, bool rtu) {
  ModbusChannel c;
  c.name = name;
  c.unit = r.text("unit");
  c.point.unit_id = rtu ? static_cast<int>(r.integer("unit_id", 1, 247)) : static_cast<int>(r.integer("unit_id", 0, 255));
  c.point.type = register_type_from_string(r.choice("register", names(register_type_names())));
  if (output && c.point.type != RegisterType::kHoldingRegister) {
    r.fail("register", "outputs must be holding registers (the analogue output is written with FC 6/16)");
  }
  c.point.address = static_cast<int>(r.integer("address", 0, 65535));
  c.point.format = data_format_from_string(r.choice("format", names(data_format_names())));
  const int count = register_count(c.point.format);
  if (c.point.address + count - 1 > 65535) {
    r.fail("address", "a " + std::string(to_string(c.point.format)) + " needs " + std::to_string(count) +
                          " registers; the last would be beyond 65535");
  }
  // The word order of a 32-bit value is the classic source of silently wrong
  // readings, so it must be stated; for 16-bit values it only matters for
  // byte-swapping modules.
  if (count == 2 || r.has("order")) c.point.order = word_order_from_string(r.choice("order", names(word_order_names())));
  c.calibration = read_calibration(r.child("calibration"));
  if (output) c.safe = r.number("safe");
  r.reject_unknown_keys();
  return c;
}

std::vector<ModbusChannel> read_channels(ConfigReader r, bool output, bool rtu) {
  std::vector<ModbusChannel> out;
  for (const auto& name : r.keys()) out.push_back(read_channel(r.child(name), name, output, rtu));
  // Two outputs on one register would fight over it.
  for (std::size_t j = 0; j < out.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      const ModbusPoint& a = out[i].point;
      const ModbusPoint& b = out[j].point;
      if (output && a.unit_id == b.unit_id && a.address < b.address + register_count(b.format) &&
          b.address < a.address + register_count(a.format)) {
        r.fail(out[j].name, "shares registers with output " + out[i].name + " (unit " + std::to_string(a.unit_id) + ")");
      }
    }
  }
  return out;
}

// Bits on the wire per character: start, data, parity, stop.
double char_bits(const ModbusConnection& k) { return 1.0 + k.data_bits + (k.parity == 'N' ? 0 : 1) + k.stop_bits; }

// The response timeout bounds a whole transaction on a serial line (the
// request leaves the UART after write() returns): it must at least cover the
// longest request plus its reply, or every such request times out.
void check_serial_timing(ConfigReader& r, const ModbusDaqConfig& c) {
  const double per_byte = char_bits(c.connection) / c.connection.baud;
  int worst_bytes = 0;
  std::vector<ModbusPoint> points;
  for (const auto& ch : c.inputs) points.push_back(ch.point);
  for (const auto& b : plan_reads(points, {c.max_gap, kMaxReadRegisters}).blocks) {
    worst_bytes = std::max(worst_bytes, 8 + 5 + 2 * b.count);  // FC 3/4 request + reply
  }
  std::vector<ModbusPoint> outputs;
  for (const auto& ch : c.outputs) outputs.push_back(ch.point);
  for (const auto& b : plan_writes(outputs).blocks) {
    // FC 6 request and echo, or FC 16 request and reply.
    worst_bytes = std::max(worst_bytes, b.count == 1 ? 8 + 8 : 9 + 2 * b.count + 8);
  }
  const double needed = worst_bytes * per_byte;
  if (c.connection.response_timeout_s < needed) {
    char text[160];
    std::snprintf(text, sizeof text, "%g s is shorter than the %d bytes of the longest request and reply take at %d baud "
                  "(%g s)", c.connection.response_timeout_s, worst_bytes, c.connection.baud, needed);
    r.fail("response_timeout_s", text);
  }
}

}  // namespace

ModbusDaqConfig read_modbus_daq(ConfigReader r, double default_period_s) {
  ModbusDaqConfig c;
  ModbusConnection& k = c.connection;
  const bool rtu = r.choice("transport", {"tcp", "rtu"}) == "rtu";
  k.transport = rtu ? ModbusTransport::kRtu : ModbusTransport::kTcp;
  // The other transport's keys may stay in the file (switching is one line);
  // they are still checked, so a typo there is not silently carried along.
  if (!rtu || r.has("host")) k.host = r.text("host");
  if (!rtu || r.has("port")) k.port = static_cast<int>(r.integer("port", 1, 65535));
  if (rtu || r.has("device")) k.device = r.text("device");
  if (rtu || r.has("baud")) k.baud = static_cast<int>(r.integer("baud", 300, 4000000));
  if (rtu || r.has("parity")) k.parity = r.choice("parity", {"N", "E", "O"})[0];
  if (rtu || r.has("data_bits")) k.data_bits = static_cast<int>(r.integer("data_bits", 5, 8));
  if (rtu || r.has("stop_bits")) k.stop_bits = static_cast<int>(r.integer("stop_bits", 1, 2));
  if (k.host.empty()) r.fail("host", "must not be empty");
  if (rtu && k.device.empty()) r.fail("device", "must not be empty");
  k.response_timeout_s = r.number("response_timeout_s", 1e-4, 10.0);
  k.reconnect_interval_s = r.number("reconnect_interval_s", 1e-3, 3600.0);
  c.poll_period_s = r.has("poll_period_s") ? r.number("poll_period_s", 1e-4, 1.0) : default_period_s;
  c.max_sample_age_s = r.number("max_sample_age_s", 1e-4, 10.0);
  if (c.max_sample_age_s < c.poll_period_s) {
    r.fail("max_sample_age_s", "must be at least the poll period (" + std::to_string(c.poll_period_s) +
                                   " s), or every sample would be stale");
  }
  c.max_gap = static_cast<int>(r.integer("max_gap", 0, kMaxReadRegisters - 2));
  if (r.has("io_priority")) c.io_priority = static_cast<int>(r.integer("io_priority", 0, 99));
  c.inputs = read_channels(r.child("inputs"), false, rtu);
  c.outputs = read_channels(r.child("outputs"), true, rtu);
  if (c.inputs.size() > kMaxInputs) r.fail("inputs", "at most " + std::to_string(kMaxInputs) + " inputs");
  if (c.outputs.size() > kMaxOutputs) r.fail("outputs", "at most " + std::to_string(kMaxOutputs) + " outputs");
  if (rtu) check_serial_timing(r, c);
  r.reject_unknown_keys();
  try {
    validate(c);  // whatever the checks above missed; should not trigger
  } catch (const std::invalid_argument& e) {
    r.fail("inputs", e.what());
  }
  return c;
}

}  // namespace rigctl
