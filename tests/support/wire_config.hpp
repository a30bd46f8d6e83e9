// The shipped quarter-car config for the end-to-end tests on the wire:
// `rigctl run` with a hardware driver against `rigctl rig-sim` on 127.0.0.1
// and a seqpacket socket in the test's own folder (test_hardware_in_the_loop,
// test_fault_matrix, test_canopen_valve_run).
//
// Its times are for a loaded 2-core test machine, in two kinds:
//  * Start-up runs mostly at normal priority (process start, the DAQ's
//    first sample; the valve's SDO configuration and our heartbeat run at
//    the valve's io_priority where SCHED_FIFO is permitted, at normal
//    priority where not): seconds, so a process that is descheduled or
//    starts from a cold cache only starts later. With an SDO timeout of
//    0.1 s (shipped once) a run failed here with "no answer within
//    sdo_timeout_s = 0.1 s".
//  * Running, the fault-to-safe chain is SCHED_FIFO threads on both sides
//    (rig-sim's plant and valve, the loop, the drivers' I/O): a CPU hog at
//    normal priority cannot delay it, the stalls of a shared VM can, by tens
//    of milliseconds. Allowed for: 10 ms replies, 100 ms (40 periods) of
//    sample age and of the valve's heartbeat. The fault bounds are stated in
//    these terms.
#pragma once

#include <string>

#include "config_edit.hpp"

namespace rigctl::test {

constexpr double kWireMaxAge = 0.1;  // [s] sample age and (unless a test is about it) heartbeat timeout

// driver: modbus, modbus_canopen, or sim for rig-sim's own copy. port: the
// DAQ's TCP port. valve_socket: the CANopen valve's socket path.
// heartbeat_timeout_s: give the shipped 0.05 where the heartbeat's loss is
// what the test measures.
inline std::string wire_config(const std::string& driver, int port, const std::string& valve_socket,
                               double heartbeat_timeout_s = kWireMaxAge) {
  std::string text = shipped_config();
  text = edit(text, "\ndriver: sim\n", "\ndriver: " + driver + "\ndriver_start_timeout_s: 30\n");
  if (port != 1502) text = edit(text, "port: 1502", "port: " + std::to_string(port));
  text = edit(text, "response_timeout_s: 0\\.002", "response_timeout_s: 0.01");
  text = edit(text, "max_sample_age_s: 0\\.0125", "max_sample_age_s: " + std::to_string(kWireMaxAge));
  text = edit(text, "actual_max_age_s: 0\\.0125", "actual_max_age_s: " + std::to_string(kWireMaxAge));
  text = edit(text, "socket_path: /run/rigctl/valve\\.sock", "socket_path: " + valve_socket);
  text = edit(text, "heartbeat_timeout_s: 0\\.05", "heartbeat_timeout_s: " + std::to_string(heartbeat_timeout_s));
  // The valve's consumer time for our heartbeat and its setpoint deadline:
  // our heartbeat and null setpoints come from SCHED_FIFO threads, our
  // setpoints from the loop, all of which a shared VM can stall by tens of
  // milliseconds (as the sample age above allows for).
  text = edit(text, "  sdo_timeout_s: 0\\.5\n", "  sdo_timeout_s: 2.0\n  valve_consumer_time_s: 1.0\n");
  text = edit(text, "  startup_timeout_s: 5\\.0 ", "  startup_timeout_s: 30 ");
  text = edit(text, "  setpoint_timeout_s: 0\\.05 ", "  setpoint_timeout_s: " + std::to_string(kWireMaxAge) + " ");
  return text;
}

// The same for `rigctl run --lock-step` against `rig-sim --lock-step`: the
// loop runs in simulated time at normal priority and waits on the wire each
// tick, so a loaded machine can hold it (and the valve's view of it) for
// longer than a paced loop at SCHED_FIFO; the wall-clock deadlines that
// remain (the valve's spool actual value and heartbeats, its setpoint
// deadline) get seconds. They are not what the lock-step tests measure: the
// fault tests run paced with the config above. (The DAQ's inputs cannot go
// stale in lock-step: each read waits for a fresh one.) The DAQ's response
// timeout too: a reply given up on would leave rig-sim's plant one step
// ahead of the loop's count.
inline std::string lock_step_wire_config(const std::string& driver, int port, const std::string& valve_socket) {
  constexpr double kDeadline = 5.0;  // [s] far beyond any stall seen here (184 ms)
  const std::string age = std::to_string(kWireMaxAge), deadline = std::to_string(kDeadline);
  std::string text = wire_config(driver, port, valve_socket);
  text = edit(text, "response_timeout_s: 0\\.01", "response_timeout_s: " + deadline);
  text = edit(text, "actual_max_age_s: " + age, "actual_max_age_s: " + deadline);
  text = edit(text, "heartbeat_timeout_s: " + age, "heartbeat_timeout_s: " + deadline);
  text = edit(text, "valve_consumer_time_s: 1\\.0", "valve_consumer_time_s: " + deadline);
  text = edit(text, "setpoint_timeout_s: " + age, "setpoint_timeout_s: " + deadline);
  return text;
}

}  // namespace rigctl::test
