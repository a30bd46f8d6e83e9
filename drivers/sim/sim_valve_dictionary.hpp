// The simulated valve's object dictionary: what it holds at power-on, the
// CiA 301 rules for writing its PDO objects, and the PDO mappings it holds.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drivers/canopen/protocol/pdo.hpp"
#include "drivers/canopen/protocol/pdo_setup.hpp"
#include "drivers/canopen/protocol/sdo.hpp"
#include "drivers/sim/sim_canopen_valve_config.hpp"

namespace rigctl {

// The dictionary at power-on.
std::vector<canopen::OdEntry> make_valve_dictionary(const SimCanopenValveConfig& config);

// The data type of an object the valve can map into the PDO of `direction`
// (nullopt: it cannot be mapped there).
std::optional<canopen::PdoType> mappable_type(canopen::PdoDirection direction, uint16_t index, uint8_t subindex);

// CiA 301's rules for a write of `value` to `entry` of the valve's PDO
// objects (0 for any other object): a mapping entry or count changes only
// while the PDO is not valid and (for an entry) its count is 0
// (0x06010000 otherwise); an entry names an object that can be mapped
// (0x06040041); the count's objects fit 8 bytes (0x06040042); the identifier
// of a valid PDO does not change (0x06090030).
uint32_t pdo_write_refusal(std::span<const canopen::OdEntry> od, const canopen::OdEntry& entry, uint32_t value);

// The mapping PDO n of `direction` holds now (raw counts: scale 1), and
// whether the PDO is valid (COB-ID bit 31 clear).
struct SimPdo {
  canopen::PdoMapping mapping;
  bool valid = false;
  uint32_t cob_id = 0;
};
SimPdo pdo_from_dictionary(std::span<const canopen::OdEntry> od, canopen::PdoDirection direction, int number);

// The value of an entry, or nullopt.
std::optional<uint32_t> od_get(std::span<const canopen::OdEntry> od, uint16_t index, uint8_t subindex);

}  // namespace rigctl
