#include "drivers/sim/sim_valve_dictionary.hpp"

#include <cmath>

#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl {

using namespace canopen;

namespace {

struct Mappable {
  uint16_t index;
  uint8_t subindex;
  PdoType type;
  PdoDirection direction;
};
// What the valve maps: what it receives (setpoints, control word) and what it sends.
constexpr Mappable kMappable[] = {
    {cia408::kControlWord, 0, PdoType::kU16, PdoDirection::kReceive},
    {cia408::kSplSetpoint, cia408::kValueSubindex, PdoType::kI16, PdoDirection::kReceive},
    {cia408::kPrsSetpoint, cia408::kValueSubindex, PdoType::kI16, PdoDirection::kReceive},
    {cia408::kStatusWord, 0, PdoType::kU16, PdoDirection::kTransmit},
    {cia408::kSplActualValue, cia408::kValueSubindex, PdoType::kI16, PdoDirection::kTransmit},
    {cia408::kPrsActualValue, cia408::kValueSubindex, PdoType::kI16, PdoDirection::kTransmit},
};

void add_pdo_objects(std::vector<OdEntry>& od, const SimCanopenValveConfig& c, PdoDirection d, int n) {
  using A = Access;
  const bool receive = d == PdoDirection::kReceive;
  const uint16_t comm = pdo_communication_index(d, n);
  const uint16_t map = pdo_mapping_index(d, n);
  const uint32_t cob = cob_id(receive ? rpdo(n) : tpdo(n), c.node_id);
  const auto timer_ms = receive ? 0U : static_cast<uint32_t>(std::lround(c.tpdo_period_s * 1000.0));
  od.push_back({comm, 0, 1, A::kReadOnly, 5});
  od.push_back({comm, kPdoCobIdSub, 4, A::kReadWrite, cob | (receive ? 0U : kPdoCobNoRtr)});
  od.push_back({comm, kPdoTransmissionTypeSub, 1, A::kReadWrite, kTransmissionEventDriven});
  od.push_back({comm, kPdoEventTimerSub, 2, A::kReadWrite, timer_ms});

  std::vector<uint32_t> entries;
  const uint16_t word = receive ? cia408::kControlWord : cia408::kStatusWord;
  entries.push_back(pdo_mapping_value({word, 0, PdoType::kU16, 1.0}));
  if (c.power_on_mapping == SimPowerOnMapping::kProfile) {
    entries.push_back(pdo_mapping_value(
        {receive ? cia408::kSplSetpoint : cia408::kSplActualValue, cia408::kValueSubindex, PdoType::kI16, 1.0}));
    if (!receive && c.with_pressure) {
      entries.push_back(pdo_mapping_value({cia408::kPrsActualValue, cia408::kValueSubindex, PdoType::kI16, 1.0}));
    }
  }
  const A access = c.fixed_mapping ? A::kReadOnly : A::kReadWrite;
  od.push_back({map, 0, 1, access, static_cast<uint32_t>(entries.size())});
  for (uint8_t i = 0; i < PdoMapping::kMaxEntries; ++i) {
    od.push_back({map, static_cast<uint8_t>(i + 1), 4, access, i < entries.size() ? entries[i] : 0U});
  }
}

// Which PDO an object of the PDO ranges belongs to.
struct PdoOf {
  PdoDirection direction = PdoDirection::kReceive;
  int number = 0;  // 0: not a PDO object
  bool mapping = false;
};
PdoOf pdo_of(uint16_t index) {
  for (int n = 1; n <= 4; ++n) {
    for (PdoDirection d : {PdoDirection::kReceive, PdoDirection::kTransmit}) {
      if (index == pdo_communication_index(d, n)) return {d, n, false};
      if (index == pdo_mapping_index(d, n)) return {d, n, true};
    }
  }
  return {};
}

// Bits the first `count` entries of a mapping take; -1 when one cannot be mapped.
int mapped_bits(std::span<const OdEntry> od, PdoDirection d, uint16_t map, uint32_t count) {
  int bits = 0;
  for (uint32_t i = 1; i <= count; ++i) {
    const auto f = decode_pdo_mapping_value(od_get(od, map, static_cast<uint8_t>(i)).value_or(0));
    const auto type = mappable_type(d, f.index, f.subindex);
    if (!type || pdo_type_bits(*type) != f.bits) return -1;
    bits += f.bits;
  }
  return bits;
}

}  // namespace

std::optional<uint32_t> od_get(std::span<const OdEntry> od, uint16_t index, uint8_t subindex) {
  for (const auto& e : od) {
    if (e.index == index && e.subindex == subindex) return e.value;
  }
  return std::nullopt;
}

std::optional<PdoType> mappable_type(PdoDirection d, uint16_t index, uint8_t subindex) {
  for (const auto& m : kMappable) {
    if (m.index == index && m.subindex == subindex && m.direction == d) return m.type;
  }
  return std::nullopt;
}

std::vector<OdEntry> make_valve_dictionary(const SimCanopenValveConfig& c) {
  using A = Access;
  std::vector<OdEntry> od = {
      {0x1000, 0, 4, A::kReadOnly, c.device_type},
      {0x1001, 0, 1, A::kReadOnly, 0},
      {0x1016, 0, 1, A::kReadOnly, 1},
      {0x1016, 1, 4, A::kReadWrite, 0},  // master heartbeat consumer: off until configured
      {0x1017, 0, 2, A::kReadWrite, c.heartbeat_period_ms},
      {0x1018, 0, 1, A::kReadOnly, 4},
      {0x1018, 1, 4, A::kReadOnly, c.vendor_id},
      {0x1018, 2, 4, A::kReadOnly, c.product_code},
      {0x1018, 3, 4, A::kReadOnly, c.revision},
      {0x1018, 4, 4, A::kReadOnly, c.serial},
      {cia408::kControlWord, 0, 2, A::kReadWrite, 0},
      {cia408::kStatusWord, 0, 2, A::kReadOnly, 0x0008},
      {cia408::kDeviceMode, 0, 1, A::kReadWrite, 0},  // 1 = setpoint via bus must be written
      {cia408::kControlMode, 0, 1, A::kReadWrite, static_cast<uint32_t>(cia408::kControlModeSpoolClosedLoop)},
      {cia408::kSplSetpoint, 0, 1, A::kReadOnly, 1},
      {cia408::kSplSetpoint, 1, 2, A::kReadWrite, 0},
      {cia408::kSplActualValue, 0, 1, A::kReadOnly, 1},
      {cia408::kSplActualValue, 1, 2, A::kReadOnly, 0},
      {cia408::kSplReferenceValue, 0, 1, A::kReadOnly, 1},
      {cia408::kSplReferenceValue, 1, 2, A::kReadOnly, static_cast<uint16_t>(c.spool_reference)},
      {cia408::kSplHoldSetpoint, 0, 1, A::kReadOnly, 1},
      {cia408::kSplHoldSetpoint, 1, 2, A::kReadWrite, 0},
      {cia408::kPrsSetpoint, 0, 1, A::kReadOnly, 1},
      {cia408::kPrsSetpoint, 1, 2, A::kReadWrite, 0},
  };
  if (c.with_pressure) {
    od.push_back({cia408::kPrsActualValue, 0, 1, A::kReadOnly, 1});
    od.push_back({cia408::kPrsActualValue, 1, 2, A::kReadOnly, 0});
  }
  add_pdo_objects(od, c, PdoDirection::kReceive, c.setpoint_rpdo);
  add_pdo_objects(od, c, PdoDirection::kTransmit, c.actual_tpdo);
  return od;
}

uint32_t pdo_write_refusal(std::span<const OdEntry> od, const OdEntry& entry, uint32_t value) {
  const PdoOf p = pdo_of(entry.index);
  if (p.number == 0) return 0;
  const uint16_t comm = pdo_communication_index(p.direction, p.number);
  const uint16_t map = pdo_mapping_index(p.direction, p.number);
  const bool valid = (od_get(od, comm, kPdoCobIdSub).value_or(kPdoCobInvalid) & kPdoCobInvalid) == 0;
  if (p.mapping) {
    if (valid) return sdo::kAbortUnsupportedAccess;
    if (entry.subindex == 0) {
      if (value > PdoMapping::kMaxEntries) return sdo::kAbortValueTooHigh;
      const int bits = mapped_bits(od, p.direction, map, value);
      if (bits < 0) return sdo::kAbortNotMappable;
      return bits > 64 ? sdo::kAbortPdoLength : 0;
    }
    if (od_get(od, map, 0).value_or(0) != 0) return sdo::kAbortUnsupportedAccess;
    const auto f = decode_pdo_mapping_value(value);
    const auto type = mappable_type(p.direction, f.index, f.subindex);
    const bool exists = od_get(od, f.index, f.subindex).has_value();
    if (value != 0 && (!type || !exists || pdo_type_bits(*type) != f.bits)) return sdo::kAbortNotMappable;
    return 0;
  }
  if (entry.subindex == kPdoCobIdSub) {
    const bool to_valid = (value & kPdoCobInvalid) == 0;
    if (to_valid && valid && (value & kPdoCobIdMask) != (entry.value & kPdoCobIdMask)) {
      return sdo::kAbortInvalidValue;  // the id of a valid PDO does not change
    }
    if ((value & 0x20000000U) != 0) return sdo::kAbortInvalidValue;  // 29-bit ids: not on this node
  }
  return 0;
}

SimPdo pdo_from_dictionary(std::span<const OdEntry> od, PdoDirection d, int n) {
  SimPdo p;
  const uint16_t comm = pdo_communication_index(d, n);
  const uint16_t map = pdo_mapping_index(d, n);
  const uint32_t cob = od_get(od, comm, kPdoCobIdSub).value_or(kPdoCobInvalid);
  p.cob_id = cob & kPdoCobIdMask;
  const uint32_t count = od_get(od, map, 0).value_or(0);
  for (uint32_t i = 1; i <= count; ++i) {
    const auto f = decode_pdo_mapping_value(od_get(od, map, static_cast<uint8_t>(i)).value_or(0));
    const auto type = mappable_type(d, f.index, f.subindex);
    if (!type || !p.mapping.add({f.index, f.subindex, *type, 1.0})) return p;  // not valid
  }
  p.valid = (cob & kPdoCobInvalid) == 0 && count > 0;
  return p;
}

}  // namespace rigctl
