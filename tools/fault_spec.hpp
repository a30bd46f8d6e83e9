// Faults that `rigctl rig-sim` injects on the far side of the wire, given on
// its command line as KIND@TIME[:ARG...], e.g.
//   silence@5:1        stop answering Modbus requests at t = 5 s for 1 s
//   drop@5             close the Modbus client's connection at 5 s
//   late@5:0.02:1      delay every Modbus reply by 20 ms, from 5 s for 1 s
//   exception@5:x_r:2  answer reads of x_r's registers with exception code 2
//   stuck@5:x_b        freeze x_b's register at its present value
//   rail@5:p1          force p1's register to the top of its range (open circuit)
//   heartbeat@5:0.5    the CANopen valve misses its heartbeats for 0.5 s
//   emcy@5:0x5000:1    the valve sends an EMCY, code 0x5000, error register 1
// Times are seconds since rig-sim started.
#pragma once

#include <string>
#include <vector>

namespace rigctl {

enum class FaultKind { kSilence, kDrop, kLate, kException, kStuck, kRail, kHeartbeat, kEmcy };

struct FaultSpec {
  FaultKind kind = FaultKind::kDrop;
  double at_s = 0.0;
  double duration_s = 0.0;  // silence, late, heartbeat; 0 = until the end
  double delay_s = 0.0;     // late
  std::string channel;      // exception, stuck, rail
  int code = 0;             // exception code, or EMCY error code
  int error_register = 0;   // emcy
  std::string text;         // as given, for messages
};

// Throws std::invalid_argument naming the spec and what is wrong.
FaultSpec parse_fault_spec(const std::string& spec);

}  // namespace rigctl
