// Reader of the `canopen:` config section (the CANopen servovalve client,
// drivers/canopen/canopen_valve.hpp). Strict like every reader: unknown keys, wrong
// types, out-of-range values and inconsistent combinations stop the program
// with `file:line: canopen.key: reason`.
//
//   canopen:
//     interface: can0                  # SocketCAN interface, or (exactly one of the two)
//     socket_path: /run/rigctl/valve.sock   # SOCK_SEQPACKET socket of the simulated valve
//     node_id: 1                       # the valve, 1..127
//     master_node_id: 127              # optional (127): our heartbeat is 0x700 + this
//     heartbeat_timeout_s: 0.05        # the valve's heartbeat must come at least this often
//     heartbeat_period_s: 0.02         # our heartbeat period
//     configure_heartbeats: true       # optional (true): write the two below at start-up
//     valve_heartbeat_period_s: 0.016  # optional (heartbeat_timeout_s / 3): 0x1017, whole ms, < heartbeat_timeout_s
//     valve_consumer_time_s: 0.05      # optional (2.5 x heartbeat_period_s): 0x1016:1, whole ms, > heartbeat_period_s
//     reset_on_start: true             # optional (true): NMT reset communication, wait for boot-up
//     boot_timeout_s: 1.0              # optional (1.0): the boot-up must follow the reset within this
//     sdo_timeout_s: 0.5               # per request; one that times out is sent once more
//     startup_timeout_s: 2.0           # optional (2.0): bounds the whole start-up
//     device_state_timeout_s: 0.5      # optional (0.5): each step of the walk to DEVICE MODE ACTIVE
//     actual_max_age_s: 0.0075         # older spool actual values are flagged invalid
//     configure_pdos: true             # optional (true): write the PDOs below into the valve (false: only check them)
//     actual_period_s: 0.001           # optional (0.001): TPDO event timer, whole ms, < actual_max_age_s
//     setpoint_timeout_s: 0.05         # optional (0.05): RPDO event timer, the valve's setpoint deadline; 0: off
//     spool_full_scale: 16384          # optional: counts for 100 %, checked against the valve's 0x6311:1
//     setpoint_output: u               # output channel written as the spool setpoint
//     actual_input: x_s                # input channel: spool actual, fraction of rated (-1..1)
//     pressure_input: p_v              # optional: pressure actual value 0x6381:1 in the TPDO, Pa
//     pressure_scale_pa: 1000          # required with pressure_input: Pa per count
//     setpoint_rpdo: 1                 # optional (1): RPDO number 1..4
//     actual_tpdo: 1                   # optional (1): TPDO number 1..4
//     startup_sdo:                     # optional: expedited SDO writes, in file order
//       device_mode: {index: 0x6042, subindex: 0, size: 1, value: 1}
//       control_word: {index: 0x6040, subindex: 0, size: 2, value: 0x0007}
//
// startup_sdo is a mapping of named writes rather than a list: ConfigReader
// gives strict, line-numbered access to mappings only, and the names make
// the error of an aborted write readable ("'device_mode' 0x6042:00 ...").
// Integers may be written in hex (0x6042); note that a leading 0 makes them octal.
#pragma once

#include "config/config_reader.hpp"
#include "drivers/canopen/canopen_valve_config.hpp"

namespace rigctl {

// `r` is the reader of the `canopen:` mapping itself.
CanopenValveConfig read_canopen_valve(ConfigReader r);

}  // namespace rigctl
