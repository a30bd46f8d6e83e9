// rig-sim's injected faults on the wire (`--fault KIND@TIME[:ARG...]`): each
// begins (and, with a duration, ends) at its plant time, on the simulated
// DAQ or the CANopen valve node. Refuses at construction what the wire
// cannot carry or what names an unknown DAQ input.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "drivers/modbus/modbus_daq_config.hpp"
#include "drivers/sim/fault_spec.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"

namespace rigctl {

class FaultSchedule {
 public:
  // Throws std::invalid_argument naming the fault.
  FaultSchedule(std::vector<FaultSpec> faults, SimModbusDaq& daq, SimCanopenValve* valve, std::ostream& out);
  // Begins and ends what is due at plant time t. Not on a real-time path of
  // its own: rig-sim's plant calls it once per period; fault changes are rare.
  void apply(double t);

 private:
  void begin(const FaultSpec& f);
  void end(const FaultSpec& f);

  std::vector<FaultSpec> faults_;
  std::vector<bool> started_, ended_;
  SimModbusDaq& daq_;
  SimCanopenValve* valve_;
  std::ostream& out_;
};

}  // namespace rigctl
