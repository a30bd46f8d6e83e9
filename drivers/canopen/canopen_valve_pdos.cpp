// CanopenValve start-up: the setpoint RPDO and the actual-value TPDO written
// into the valve by the CiA 301 sequence (protocol/pdo_setup.hpp) and read
// back. A valve that refuses a write fails start-up naming the object and
// the abort code; one that holds something else afterwards (or, with
// configure_pdos off, holds another mapping than the config's) fails naming
// the object, what it holds and what was expected.
#include <cmath>

#include "drivers/canopen/canopen_text.hpp"
#include "drivers/canopen/canopen_valve.hpp"

namespace rigctl {

using namespace canopen;
using canopen_text::hex;
using canopen_text::od_address;

namespace {
uint16_t whole_ms(double s) { return static_cast<uint16_t>(std::lround(s * 1000.0)); }
}  // namespace

PdoSetup CanopenValve::pdo_setup(PdoDirection direction) const {
  const bool setpoint = direction == PdoDirection::kReceive;
  PdoSetup s;
  s.direction = direction;
  s.number = setpoint ? config_.setpoint_rpdo : config_.actual_tpdo;
  s.cob_id = setpoint ? setpoint_cob_ : actual_cob_;
  s.mapping = setpoint ? rpdo_map_ : tpdo_map_;
  // For an RPDO the event timer is the deadline of the next setpoint; for
  // a TPDO the period the valve sends it with.
  s.event_timer_ms = whole_ms(setpoint ? config_.setpoint_timeout_s : config_.actual_period_s);
  return s;
}

void CanopenValve::configure_pdos(int64_t deadline_ns) {
  set_up_pdo(pdo_setup(PdoDirection::kReceive), deadline_ns);
  set_up_pdo(pdo_setup(PdoDirection::kTransmit), deadline_ns);
}

void CanopenValve::set_up_pdo(const PdoSetup& setup, int64_t deadline_ns) {
  const std::string name = pdo_name(setup);
  const uint16_t comm = pdo_communication_index(setup.direction, setup.number);
  if (config_.configure_pdos) {
    const uint32_t cob = *sdo_read(comm, kPdoCobIdSub, name + " COB-ID", true, deadline_ns);
    for (const PdoObjectValue& w : pdo_setup_writes(setup, cob)) {
      sdo_write({w.what, w.index, w.subindex, w.size, w.value}, deadline_ns);
    }
  }
  std::string entries;
  for (const PdoObjectValue& r : pdo_setup_read_back(setup)) {
    const uint32_t held = *sdo_read(r.index, r.subindex, r.what, true, deadline_ns);
    if (((held ^ r.value) & r.compare_mask) != 0) {
      fail(name + " read back: " + r.what + " " + od_address(r.index, r.subindex) + " holds " + hex(held, 2 * r.size) +
           ", expected " + hex(r.value, 2 * r.size) +
           (config_.configure_pdos ? ": the valve did not keep what was written"
                                   : " (configure_pdos is off: map the valve's PDO as configured, or turn it on)"));
    }
    if (r.index == pdo_mapping_index(setup.direction, setup.number) && r.subindex > 0) entries += " " + hex(held, 8);
  }
  events_.push(prefix() + name + (config_.configure_pdos ? " configured and read back" : " read back") +
               ": COB-ID " + hex(setup.cob_id, 3) + ", objects" + entries + ", transmission type " +
               std::to_string(setup.transmission_type) + ", event timer " + std::to_string(setup.event_timer_ms) + " ms");
}

}  // namespace rigctl
