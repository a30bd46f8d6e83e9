// What the CANopen servovalve client needs to know, as read from the
// `canopen:` config section (config/canopen_reader.hpp). Plain data; the
// defaults here are the reader's defaults for optional keys.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rigctl {

// One expedited SDO download done at start-up, in list order.
struct SdoWrite {
  std::string name;       // for messages, e.g. "device_mode"
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t size = 1;       // bytes, 1..4
  uint32_t value = 0;     // low `size` bytes are sent (negative values as two's complement)
};

struct CanopenValveConfig {
  // Exactly one of the two: a SocketCAN interface, or a SOCK_SEQPACKET unix
  // socket path (simulated valve, tests).
  std::string interface;
  std::string socket_path;

  uint8_t node_id = 1;          // the valve
  uint8_t master_node_id = 127; // ours: our heartbeat goes out on 0x700 + master_node_id

  double heartbeat_timeout_s = 0.05;  // our consumer time for the valve's heartbeat
  double heartbeat_period_s = 0.02;   // our heartbeat producer period
  // Written to the valve at start-up when configure_heartbeats is set:
  // 0x1017 (its producer period) and 0x1016:1 (its consumer time for our
  // heartbeat, after which it goes to its fail-safe). Whole milliseconds.
  bool configure_heartbeats = true;
  double valve_heartbeat_period_s = 0.01;
  double valve_consumer_time_s = 0.05;

  bool reset_on_start = true;   // NMT reset communication and wait for the boot-up first
  double boot_timeout_s = 1.0;  // the boot-up must follow the reset within this (and the start-up timeout)
  double sdo_timeout_s = 0.5;   // per SDO request; one that times out is sent once more
  // SCHED_FIFO priority of the I/O thread, and of the start-up thread while
  // it produces our heartbeat (0: normal scheduling).
  int io_priority = 0;
  double startup_timeout_s = 2.0;  // bounds the whole of start(): connect, boot-up, SDO, operational, ACTIVE
  double device_state_timeout_s = 0.5;  // each step of the walk to DEVICE MODE ACTIVE must be taken within this
  std::vector<SdoWrite> startup_sdo;

  // PDOs (CiA 408 default p/Q mapping, drivers/canopen/protocol/cia408.hpp):
  // RPDO n: control word, spool setpoint; TPDO n: status word, spool actual
  // value [, pressure actual value]. Written into the valve at start-up with
  // the CiA 301 sequence (configure_pdos) and always read back and checked.
  int setpoint_rpdo = 1;
  int actual_tpdo = 1;
  bool configure_pdos = true;        // false: the valve's PDOs are only read back and checked
  double actual_period_s = 0.001;    // TPDO event timer: the valve sends its actual value this often (whole ms)
  double setpoint_timeout_s = 0.05;  // RPDO event timer: no setpoint for this long and the valve faults to its safe state (whole ms; 0: off)
  double actual_max_age_s = 0.0075;  // an older spool actual value is flagged invalid
  // Counts of the spool setpoint/actual value that mean 100 %: 0 takes the
  // valve's reference value 0x6311:1; another value is checked against it
  // (and used where the valve has no such object).
  int spool_full_scale = 0;

  std::string setpoint_output = "u";  // output channel the composing driver feeds to write_setpoint()
  std::string actual_input = "x_s";   // spool actual, fraction of rated opening, -1..1
  std::string pressure_input;         // empty: no pressure in the TPDO
  double pressure_scale_pa = 1.0;     // Pa per count of the pressure actual value
};

}  // namespace rigctl
