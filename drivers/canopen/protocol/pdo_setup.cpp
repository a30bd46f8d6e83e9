#include "drivers/canopen/protocol/pdo_setup.hpp"

#include <cstdio>

namespace rigctl::canopen {

namespace {

std::string hex8(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08X", static_cast<unsigned>(v));
  return b;
}

std::string entry_what(const std::string& pdo, std::size_t i, uint32_t value) {
  return pdo + " mapping entry " + std::to_string(i + 1) + " (" + hex8(value) + ")";
}

}  // namespace

std::string pdo_name(const PdoSetup& s) {
  return std::string(s.direction == PdoDirection::kReceive ? "RPDO" : "TPDO") + std::to_string(s.number);
}

std::vector<PdoObjectValue> pdo_setup_writes(const PdoSetup& s, uint32_t cob_as_read) {
  const std::string name = pdo_name(s);
  const uint16_t comm = pdo_communication_index(s.direction, s.number);
  const uint16_t map = pdo_mapping_index(s.direction, s.number);
  // Keep what the device says about RTR and the frame format; the id is ours.
  const uint32_t cob = (cob_as_read & (kPdoCobNoRtr | 0x20000000U)) | (s.cob_id & kPdoCobIdMask);
  std::vector<PdoObjectValue> w;
  w.push_back({name + " disabled (COB-ID bit 31)", comm, kPdoCobIdSub, 4, cob | kPdoCobInvalid});
  w.push_back({name + " mapping cleared (count 0)", map, 0, 1, 0});
  for (std::size_t i = 0; i < s.mapping.size(); ++i) {
    const uint32_t v = pdo_mapping_value(s.mapping[i]);
    w.push_back({entry_what(name, i, v), map, static_cast<uint8_t>(i + 1), 4, v});
  }
  w.push_back({name + " number of mapped objects", map, 0, 1, static_cast<uint32_t>(s.mapping.size())});
  w.push_back({name + " transmission type", comm, kPdoTransmissionTypeSub, 1, s.transmission_type});
  w.push_back({name + " event timer (ms)", comm, kPdoEventTimerSub, 2, s.event_timer_ms});
  w.push_back({name + " enabled (COB-ID)", comm, kPdoCobIdSub, 4, cob});
  return w;
}

std::vector<PdoObjectValue> pdo_setup_read_back(const PdoSetup& s) {
  const std::string name = pdo_name(s);
  const uint16_t comm = pdo_communication_index(s.direction, s.number);
  const uint16_t map = pdo_mapping_index(s.direction, s.number);
  std::vector<PdoObjectValue> r;
  r.push_back({name + " number of mapped objects", map, 0, 1, static_cast<uint32_t>(s.mapping.size())});
  for (std::size_t i = 0; i < s.mapping.size(); ++i) {
    const uint32_t v = pdo_mapping_value(s.mapping[i]);
    r.push_back({entry_what(name, i, v), map, static_cast<uint8_t>(i + 1), 4, v});
  }
  r.push_back({name + " transmission type", comm, kPdoTransmissionTypeSub, 1, s.transmission_type});
  r.push_back({name + " event timer (ms)", comm, kPdoEventTimerSub, 2, s.event_timer_ms});
  r.push_back({name + " COB-ID (valid, identifier)", comm, kPdoCobIdSub, 4, s.cob_id & kPdoCobIdMask,
               kPdoCobInvalid | kPdoCobIdMask});
  return r;
}

}  // namespace rigctl::canopen
