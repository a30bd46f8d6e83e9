// Reader of the `modbus:` section: how to reach the DAQ module and the
// register map of every analogue input and output. Strict like every section:
// each key required unless marked optional below, unknown keys rejected,
// errors name file, line, key path and reason (ConfigError).
//
//   modbus:
//     transport: tcp               # tcp | rtu
//     host: 127.0.0.1              # tcp: required; rtu: optional, checked, unused
//     port: 1502                   # tcp: required (1..65535); rtu: optional, checked, unused
//     device: /dev/ttyUSB0         # rtu: required; tcp: optional, checked, unused
//     baud: 115200                 # rtu: required; tcp: optional ...
//     parity: N                    # rtu: N | E | O
//     data_bits: 8                 # rtu: 5..8
//     stop_bits: 1                 # rtu: 1 | 2
//     response_timeout_s: 0.002    # whole reply; rtu: at least the frames' transmission time
//     reconnect_interval_s: 0.5
//     poll_period_s: 0.0025        # optional: the loop period
//     max_sample_age_s: 0.0075     # >= poll_period_s; older inputs are stale
//     max_gap: 4                   # unused registers a read may span (0: never)
//     io_priority: 79              # optional, default 0: SCHED_FIFO priority of the I/O thread
//                                  # (0 = normal scheduling); just below the loop's
//     inputs:                      # name -> channel, at most 24
//       x_r: {unit: m, unit_id: 1, register: input, address: 0, format: int16,
//             calibration: {gain: 6.1035e-6, offset: 0.0}}
//       p1:  {unit: Pa, unit_id: 1, register: input, address: 5, format: float32, order: low_first,
//             calibration: {table: {raw: [0, 1000, 2000], si: [0.0, 1.0e7, 2.05e7]}}}
//     outputs:                     # name -> channel, at most 4, holding registers only
//       u: {unit: "1", unit_id: 1, register: holding, address: 0, format: int16,
//           calibration: {gain: 3.0518e-5, offset: 0.0}, safe: 0.0}
//
// Channel keys: unit (SI unit text), unit_id (0..255; rtu 1..247), register
// (input | holding), address (0-based protocol address), format (int16 uint16
// int32 uint32 float32), order (high_first low_first high_first_byte_swapped
// low_first_byte_swapped, or abcd cdab badc dcba; required for 32-bit
// formats, optional for 16-bit ones where it defaults to high_first),
// calibration (either gain + offset, or table with raw and si lists: raw
// strictly increasing, si strictly monotonic), safe (outputs only: the SI
// value for the safe state).
#pragma once

#include "config/config_reader.hpp"
#include "drivers/modbus/modbus_daq_config.hpp"

namespace rigctl {

// r: the `modbus:` mapping itself. default_period_s: the loop period, the
// default of poll_period_s.
ModbusDaqConfig read_modbus_daq(ConfigReader r, double default_period_s);

}  // namespace rigctl
