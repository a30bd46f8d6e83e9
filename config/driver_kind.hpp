// `driver:` of a config: what the loop reads from and writes to. The
// questions the rest of the program asks of a driver kind are answered here,
// each by one exhaustive switch, so that a new driver kind has to answer them.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "config/kind_names.hpp"

namespace rigctl {

enum class DriverKind : uint8_t {
  kSim,            // the simulated plant in process
  kModbus,         // sensors and valve output on a Modbus DAQ
  kModbusCanopen,  // sensors on the Modbus DAQ, valve on CANopen
};

constexpr std::string_view to_string(DriverKind k) {
  switch (k) {
    case DriverKind::kSim: return "sim";
    case DriverKind::kModbus: return "modbus";
    case DriverKind::kModbusCanopen: return "modbus_canopen";
  }
  return "unknown";
}

template <>
struct KindNames<DriverKind> {
  static constexpr std::string_view noun = "driver";
  static constexpr std::array known{DriverKind::kSim, DriverKind::kModbus, DriverKind::kModbusCanopen};
};

// Steps the simulated plant in process: no hardware, so the output
// converters of `outputs:` are the driver's own and simulated time may run
// faster than the wall clock.
constexpr bool is_simulated(DriverKind k) {
  switch (k) {
    case DriverKind::kSim: return true;
    case DriverKind::kModbus: return false;
    case DriverKind::kModbusCanopen: return false;
  }
  return false;
}

// Reads the sensors (and, without CANopen, writes the valve) over the
// config's `modbus:` DAQ, which it then requires.
constexpr bool uses_modbus_daq(DriverKind k) {
  switch (k) {
    case DriverKind::kSim: return false;
    case DriverKind::kModbus: return true;
    case DriverKind::kModbusCanopen: return true;
  }
  return false;
}

// Drives the valve over the config's `canopen:` node, which it then requires.
constexpr bool uses_canopen_valve(DriverKind k) {
  switch (k) {
    case DriverKind::kSim: return false;
    case DriverKind::kModbus: return false;
    case DriverKind::kModbusCanopen: return true;
  }
  return false;
}

}  // namespace rigctl
