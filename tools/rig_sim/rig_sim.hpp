// `rigctl rig-sim`: the simulated rig on the far side of the wire. One
// process steps the configured plant in real time and exposes it as the
// physical rig's hardware does: a Modbus DAQ server whose input registers are
// the sensors (calibration applied in reverse) and whose holding register is
// the valve's analogue command, and/or a CANopen valve node on a seqpacket
// socket path. Faults are injected at given times.
#pragma once

#include <atomic>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "drivers/sim/fault_spec.hpp"

namespace rigctl {

struct RigSimOptions {
  std::string config_path;
  std::string case_name;
  std::string modbus_tcp;   // "HOST:PORT" (port 0: pick one and print it)
  std::string modbus_rtu;   // serial device path
  std::string can_socket;   // seqpacket socket path for the CANopen valve
  std::vector<std::string> valve_options;  // the simulated valve's behaviours (drivers/sim/sim_canopen_valve_config.hpp)
  std::optional<double> duration_s;  // default: until SIGINT/SIGTERM
  std::vector<FaultSpec> faults;
  // The DAQ module's output watchdog: no write from the controller for this
  // long and the outputs go to their `safe:` values until writes resume, as
  // I/O modules do (a dead link cannot carry the controller's safe command).
  // 0: off.
  double output_watchdog_s = 0.1;
  // Lock-step (tests, with `rigctl run --lock-step`): the plant steps one
  // loop period per exchange with the controller, not by the clock. The
  // exchange is the DAQ's read of the first input's registers: the first
  // one answers the plant's initial state, each later one first steps the
  // plant with the command written (or the CANopen valve's spool, once the
  // valve has taken every frame sent before the request) and then answers.
  // Plant time is then the controller's tick count, as in `run --fast`, and
  // the faults' times are plant times.
  bool lock_step = false;
};

// Prints "rig-sim: modbus listening on HOST:PORT" and "rig-sim: canopen
// valve on PATH" once ready (tests wait for these lines), then runs.
void run_rig_sim(const RigSimOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
