// What the Modbus DAQ is, on both sides of the wire: how to reach it and which
// signal sits in which registers with which calibration. The client
// (ModbusDaq), the simulated module (SimModbusDaq) and the config reader
// share it, so the two ends cannot disagree on the register map.
#pragma once

#include <string>
#include <vector>

#include "drivers/modbus/calibration.hpp"
#include "drivers/modbus/modbus_codec.hpp"

namespace rigctl {

enum class ModbusTransport { kTcp, kRtu };

struct ModbusConnection {
  ModbusTransport transport = ModbusTransport::kTcp;
  // TCP. The client resolves host with getaddrinfo (names and IPv6 work); the
  // simulated server listens on an IPv4 address. Port 0 (server only): pick a
  // free port, reported by SimModbusDaq::port().
  std::string host = "127.0.0.1";
  int port = 502;
  // RTU (serial line).
  std::string device;
  int baud = 115200;
  char parity = 'N';  // 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  // Longest wait for a whole reply (first byte to last, see modbus_link.cpp).
  // Must be tight: libmodbus's default of 500 ms is 200 loop periods.
  double response_timeout_s = 0.002;
  // Wait between connection attempts after a loss (and the TCP connect timeout).
  double reconnect_interval_s = 0.5;
};

// One analogue signal. Inputs: raw register value -> calibration.to_si ->
// SI. Outputs: SI -> calibration.to_raw -> registers.
struct ModbusChannel {
  std::string name;  // run-file column name, e.g. "x_r"
  std::string unit;  // SI unit, e.g. "m", "Pa", "1"
  ModbusPoint point;
  Calibration calibration;
  // Outputs only: the SI value written before the loop's first command, in
  // place of a NaN command, on make_safe() and on stop() (the valve's null).
  double safe = 0.0;
};

struct ModbusDaqConfig {
  ModbusConnection connection;
  std::vector<ModbusChannel> inputs;   // at most kMaxInputs
  std::vector<ModbusChannel> outputs;  // at most kMaxOutputs; holding registers
  double max_sample_age_s = 0.0075;    // older inputs are stale (Sample::status bit)
  double poll_period_s = 0.0025;       // the I/O thread's cycle, normally the loop period
  int max_gap = 4;                     // ReadPlanOptions::max_gap
  // SCHED_FIFO priority of the I/O thread, 1..99, or 0 for normal scheduling.
  // The loop's inputs are only as fresh as this thread is punctual: on a
  // loaded machine a normal-priority I/O thread misses its period and the
  // inputs go stale. Just below the loop's priority is the natural choice.
  int io_priority = 0;
  // Lock-step (tests against `rigctl rig-sim --lock-step`, in simulated
  // time; never on a rig): after the first sample the I/O thread has no clock
  // of its own. Each read_inputs() after the first runs one whole cycle,
  // outputs first, then inputs, and waits for it, so the far side's plant
  // steps once per loop tick with the command of the tick before, as the
  // simulated driver's does. The loop then waits on the wire: fine in
  // simulated time, not in a paced run.
  bool lock_step = false;
};

// Throws std::invalid_argument naming the first problem: counts, ranges,
// outputs not in holding registers or overlapping, an unplannable read.
void validate(const ModbusDaqConfig& config);

// "127.0.0.1:1502" or "/dev/ttyUSB0", for messages.
std::string endpoint_name(const ModbusConnection& connection);

}  // namespace rigctl
