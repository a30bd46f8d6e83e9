#include "drivers/modbus/modbus_daq_config.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "drivers/modbus/modbus_write_plan.hpp"
#include "rt/sample.hpp"

namespace rigctl {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("modbus config: " + what);
}

std::vector<ModbusPoint> points_of(const std::vector<ModbusChannel>& channels) {
  std::vector<ModbusPoint> points;
  for (const auto& c : channels) points.push_back(c.point);
  return points;
}

// plan_*() name points by index; the channel's name is what a user recognises.
template <typename Plan>
void check_plan(const std::vector<ModbusChannel>& channels, const char* kind, Plan plan) {
  try {
    plan(points_of(channels));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("modbus config: ") + kind + ": " + e.what());
  }
}

}  // namespace

void validate(const ModbusDaqConfig& c) {
  const ModbusConnection& k = c.connection;
  if (k.transport == ModbusTransport::kTcp) {
    require(!k.host.empty(), "tcp needs a host");
    require(k.port >= 0 && k.port <= 65535, "port must be in 0..65535");
  } else {
    require(!k.device.empty(), "rtu needs a device");
    require(k.baud > 0, "baud must be positive");
    require(k.parity == 'N' || k.parity == 'E' || k.parity == 'O', "parity must be N, E or O");
    require(k.data_bits >= 5 && k.data_bits <= 8, "data_bits must be in 5..8");
    require(k.stop_bits == 1 || k.stop_bits == 2, "stop_bits must be 1 or 2");
    for (const auto* list : {&c.inputs, &c.outputs}) {
      for (const auto& ch : *list) {
        // Unit 0 is the RTU broadcast address: nobody answers it.
        require(ch.point.unit_id >= 1 && ch.point.unit_id <= 247,
                ch.name + ": RTU unit ids are 1..247, got " + std::to_string(ch.point.unit_id));
      }
    }
  }
  // libmodbus takes whole microseconds and rejects a zero timeout.
  require(std::isfinite(k.response_timeout_s) && k.response_timeout_s >= 1e-6 && k.response_timeout_s <= 60.0,
          "response_timeout_s must be in [1e-6, 60]");
  require(std::isfinite(k.reconnect_interval_s) && k.reconnect_interval_s >= 1e-3 && k.reconnect_interval_s <= 3600.0,
          "reconnect_interval_s must be in [0.001, 3600]");
  require(c.inputs.size() <= kMaxInputs, "at most " + std::to_string(kMaxInputs) + " inputs");
  require(c.outputs.size() <= kMaxOutputs, "at most " + std::to_string(kMaxOutputs) + " outputs");
  require(std::isfinite(c.poll_period_s) && c.poll_period_s >= 1e-4 && c.poll_period_s <= 1.0,
          "poll_period_s must be in [0.0001, 1]");
  require(std::isfinite(c.max_sample_age_s) && c.max_sample_age_s >= c.poll_period_s,
          "max_sample_age_s must be at least poll_period_s (else every sample is stale)");
  require(c.max_gap >= 0 && c.max_gap <= kMaxReadRegisters - 2, "max_gap must be in 0..123");
  require(c.io_priority >= 0 && c.io_priority <= 99, "io_priority must be in 0..99");
  for (const auto& ch : c.outputs) require(std::isfinite(ch.safe), ch.name + ": safe value must be finite");
  check_plan(c.inputs, "inputs", [&](const std::vector<ModbusPoint>& p) { plan_reads(p, {c.max_gap, kMaxReadRegisters}); });
  check_plan(c.outputs, "outputs", [](const std::vector<ModbusPoint>& p) { plan_writes(p); });
}

std::string endpoint_name(const ModbusConnection& k) {
  if (k.transport == ModbusTransport::kRtu) return k.device;
  return k.host + ":" + std::to_string(k.port);
}

}  // namespace rigctl
