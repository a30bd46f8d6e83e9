// Modbus TCP on loopback: one I/O cycle of the rig's DAQ driver (read every
// input, write the output, as planned from config/quarter_car.yaml) against a
// bare libmodbus client doing the same requests at the same period and
// priority, both against the simulated DAQ (SimModbusDaq).
#include <modbus/modbus.h>
#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>
#include <thread>

#include "drivers/modbus/modbus_daq.hpp"
#include "drivers/modbus/modbus_link.hpp"
#include "drivers/modbus/modbus_write_plan.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "rt/histogram.hpp"
#include "tools/bench/io_support.hpp"

namespace rigctl::bench::io {

namespace {

struct ModbusPair {
  Json json;
  DistributionSummary driver, bare;
};

// The driver: its I/O thread's own cycle times (ModbusDaq::io_latency)
// while a loop writes its output each period.
Json driver_cycles(Context& ctx, const ModbusDaqConfig& client, const Placement& where, int64_t cycles, int64_t period_ns,
                   DistributionSummary& cycle_times) {
  ModbusDaq daq(client);
  {
    PinnedScope pin(where.client_cpu);  // the I/O thread starts here and keeps the pin
    daq.start(2.0);
  }
  const int64_t start = mono_ns();
  for (int64_t k = 1; k <= cycles && !ctx.stop.load(); ++k) {
    const double u = 0.1 * std::sin(static_cast<double>(k) * 0.01);
    daq.write_outputs(&u, 1);  // what the loop does each tick
    sleep_until_ns(start + k * period_ns);
  }
  cycle_times = daq.io_latency();
  const ModbusDaqCounters c = daq.counters();
  daq.stop();
  Json d = Json::object();
  d["what"] = "ModbusDaq I/O thread, one cycle = every planned read + the output write";
  d["scheduling"] = client.io_priority > 0 ? "SCHED_FIFO " + std::to_string(client.io_priority) + " requested" : "normal";
  d["cycle_time"] = latency_json(cycle_times);
  d["timeouts"] = c.timeouts;
  d["protocol_errors"] = c.protocol_errors;
  d["cycle_overruns"] = c.cycle_overruns;
  return d;
}

// One bare libmodbus client's cycles (on its own thread): every read of
// the plan, then the writes. Returns an error text, "" when it ran.
std::string bare_client_loop(Context& ctx, const ModbusDaqConfig& client, const ReadPlan& reads, const WritePlan& writes,
                             int64_t cycles, int64_t period_ns, int64_t& failures, DistributionSummary& cycle_times) {
  modbus_t* mb = modbus_new_tcp_pi(client.connection.host.c_str(), std::to_string(client.connection.port).c_str());
  if (mb == nullptr) return "modbus_new_tcp_pi failed";
  const auto timeout_us = static_cast<uint32_t>(std::llround(client.connection.response_timeout_s * 1e6));
  modbus_set_response_timeout(mb, timeout_us / 1000000u, timeout_us % 1000000u);
  if (modbus_connect(mb) != 0) {
    const std::string error = std::string("connect: ") + modbus_strerror(errno);
    modbus_free(mb);
    return error;
  }
  DurationHistogram hist(1000, 20000);
  std::vector<uint16_t> buffer(kMaxReadRegisters);
  uint16_t out_regs[kMaxWriteRegisters] = {};
  int64_t next = mono_ns();
  for (int64_t k = 0; k < cycles && !ctx.stop.load(); ++k) {
    const int64_t t0 = mono_ns();
    bool ok = true;
    for (const auto& blk : reads.blocks) {
      modbus_set_slave(mb, blk.unit_id);
      const int rc = blk.type == RegisterType::kInputRegister
                         ? modbus_read_input_registers(mb, blk.address, blk.count, buffer.data())
                         : modbus_read_registers(mb, blk.address, blk.count, buffer.data());
      ok = ok && rc == blk.count;
    }
    out_regs[0] = static_cast<uint16_t>(k);
    for (const auto& blk : writes.blocks) {
      modbus_set_slave(mb, blk.unit_id);
      const int rc = blk.count == 1 ? modbus_write_register(mb, blk.address, out_regs[0])
                                    : modbus_write_registers(mb, blk.address, blk.count, out_regs);
      ok = ok && rc == (blk.count == 1 ? 1 : blk.count);
    }
    if (ok) {
      hist.record(mono_ns() - t0);
    } else {
      // The driver's recovery (ModbusLink::drain): a late reply must not
      // be taken for the next request's, or the client stays one reply
      // behind for good. Wait out one response timeout, then flush.
      ++failures;
      sleep_until_ns(mono_ns() + static_cast<int64_t>(timeout_us) * 1000);
      modbus_flush(mb);
    }
    next += period_ns;
    sleep_until_ns(next);
  }
  modbus_close(mb);
  modbus_free(mb);
  cycle_times = hist.summary();
  return "";
}

// A bare libmodbus client, the driver's requests, period and priority.
Json bare_cycles(Context& ctx, const ModbusDaqConfig& client, const Placement& where, int64_t cycles, int64_t period_ns,
                 DistributionSummary& cycle_times) {
  std::vector<ModbusPoint> in_points, out_points;
  for (const auto& ch : client.inputs) in_points.push_back(ch.point);
  for (const auto& ch : client.outputs) out_points.push_back(ch.point);
  const ReadPlan reads = plan_reads(in_points, {client.max_gap, kMaxReadRegisters});
  const WritePlan writes = plan_writes(out_points);
  Json b = Json::object();
  std::string error;
  int64_t failures = 0;
  std::optional<PinnedScope> pin;
  pin.emplace(where.client_cpu);
  std::thread t([&] {
    b["scheduling"] = set_fifo(client.io_priority);
    error = bare_client_loop(ctx, client, reads, writes, cycles, period_ns, failures, cycle_times);
  });
  pin.reset();
  t.join();
  if (!error.empty()) {
    b["status"] = "error";
    b["error"] = error;
  }
  b["what"] = "bare libmodbus client loop (modbus_read_input_registers + modbus_write_register), same plan";
  b["cycle_time"] = latency_json(cycle_times);
  b["failed_cycles"] = failures;
  return b;
}

ModbusPair modbus_pair(Context& ctx, const ModbusDaqConfig& server_config, const Placement& where, double seconds) {
  ModbusPair out;
  Json& j = out.json;
  j = Json::object();
  j["server_cpu"] = where.server_cpu;
  j["client_cpu"] = where.client_cpu;
  SimModbusDaq server(server_config);
  {
    PinnedScope pin(where.server_cpu);
    server.start();
  }
  const ModbusDaqConfig client = server.client_config();
  std::vector<double> inputs(client.inputs.size(), 0.0);
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i] = 0.001 * static_cast<double>(i + 1);
  server.set_inputs(inputs.data(), inputs.size());
  const int64_t period_ns = std::llround(client.poll_period_s * 1e9);
  const int64_t cycles = std::llround(seconds / client.poll_period_s);
  j["driver"] = driver_cycles(ctx, client, where, cycles, period_ns, out.driver);
  j["bare_libmodbus"] = bare_cycles(ctx, client, where, cycles, period_ns, out.bare);
  server.stop();
  j["ratio_driver_over_bare"] = comparison_row(out.driver, out.bare);
  return out;
}

}  // namespace

Json modbus_bench(Context& ctx, Table& table) {
  const RigConfig config = load_rig_config(ctx.quarter_car_config);
  if (!config.modbus) return skipped(ctx.quarter_car_config + " has no modbus: section");
  ModbusDaqConfig server_config = *config.modbus;
  server_config.connection.transport = ModbusTransport::kTcp;
  server_config.connection.host = "127.0.0.1";
  server_config.connection.port = 0;
  const double seconds = ctx.pick(5.0, 0.5);

  Json j = Json::object();
  std::vector<ModbusPoint> in_points, out_points;
  for (const auto& ch : server_config.inputs) in_points.push_back(ch.point);
  for (const auto& ch : server_config.outputs) out_points.push_back(ch.point);
  const ReadPlan reads = plan_reads(in_points, {server_config.max_gap, kMaxReadRegisters});
  const WritePlan writes = plan_writes(out_points);
  std::string requests;
  for (const auto& b : reads.blocks) requests += (requests.empty() ? "" : ", ") + describe_request(false, b.type, b.unit_id, b.address, b.count);
  for (const auto& b : writes.blocks) requests += ", " + describe_request(true, RegisterType::kHoldingRegister, b.unit_id, b.address, b.count);
  j["server"] = "SimModbusDaq on 127.0.0.1 (normal priority)";
  j["cycle"] = requests;
  j["period_us"] = static_cast<int64_t>(std::llround(server_config.poll_period_s * 1e6));
  j["response_timeout_ms"] = server_config.connection.response_timeout_s * 1e3;
  j["seconds_each"] = seconds;
  for (const auto& where : placements()) {
    if (ctx.stop.load()) break;
    ModbusPair pair = modbus_pair(ctx, server_config, where, seconds);
    table.row(cells("Modbus TCP cycle, " + where.name, "rigctl driver", pair.driver));
    table.row(cells("", "bare libmodbus", pair.bare));
    ratio_row(table, pair.json["ratio_driver_over_bare"]);
    j[where.name] = pair.json;
  }
  j["status"] = "ok";
  return j;
}

}  // namespace rigctl::bench::io
