// What the simulated CiA 408 valve node (sim_canopen_valve.hpp) is like: its
// identity, timing, and the behaviours of real valves the client must cope
// with, each an option (`rigctl rig-sim --valve KEY[=VALUE]`, parsed here).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "drivers/canopen/protocol/cia408.hpp"

namespace rigctl {

// The PDO mapping the node has at power-on (before any client maps it).
enum class SimPowerOnMapping : uint8_t {
  kProfile,  // RPDO: control word, spool setpoint; TPDO: status word, spool actual [, pressure] (what the client maps)
  kMinimal,  // RPDO: control word only; TPDO: status word only (a valve as shipped)
};

struct SimCanopenValveConfig {
  uint8_t node_id = 1;
  double spool_time_constant_s = 0.004;  // first-order lag of the spool
  double tpdo_period_s = 0.001;          // spool actual value sent this often while operational (until 0x1800:5 is written)
  int setpoint_rpdo = 1;
  int actual_tpdo = 1;
  bool with_pressure = false;            // the node has the pressure actual value 0x6381:1 (mapped at power-on with kProfile)
  double pressure_scale_pa = 1.0;        // Pa per count
  uint16_t heartbeat_period_ms = 0;      // 0x1017 at power-on (0: off until configured)
  uint32_t vendor_id = 0x0000'0000;      // 0x1018 identity (simulated)
  uint32_t product_code = 0x0000'0408;
  uint32_t revision = 0x0001'0000;
  uint32_t serial = 1;

  // ---- behaviours (options)
  uint32_t device_type = canopen::cia408::kProfileNumber;  // 0x1000: 401 makes it a CiA 401 I/O module
  int16_t spool_reference = canopen::cia408::kFullScale;  // 0x6311:1, counts for 100 %
  double boot_delay_s = 0.0;  // after power-on and each reset: silent for this long, then the boot-up message
  SimPowerOnMapping power_on_mapping = SimPowerOnMapping::kProfile;
  bool fixed_mapping = false;      // the mapping objects are read-only (a valve with a static mapping)
  bool segmented_uploads = false;  // every SDO upload answered segmented
  // The device state machine goes no further than this (DISABLED: an enable
  // input that is not wired); nullopt: up to DEVICE MODE ACTIVE.
  std::optional<canopen::cia408::ValveState> stall_at;
};

// Applies one option, KEY or KEY=VALUE:
//   device_type=401            0x1000 (decimal or 0x hex)
//   spool_reference=8192       0x6311:1
//   boot_delay=0.02            seconds
//   power_on_mapping=minimal   profile | minimal
//   fixed_mapping              mapping objects read-only
//   segmented_uploads          uploads answered segmented
//   stall=disabled             init | disabled | hold
// Throws std::invalid_argument naming the option and the known keys.
void apply_sim_valve_option(const std::string& option, SimCanopenValveConfig& config);

}  // namespace rigctl
