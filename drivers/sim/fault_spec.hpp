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
//   hold@5:0.5         the valve drops from DEVICE MODE ACTIVE to HOLD for 0.5 s
// Times are seconds since rig-sim started.
//
// The same syntax injects faults into the simulated driver of `rigctl run`
// (`--fault`, repeatable, or the config's `faults:` list; drivers/sim/sim_faults.hpp),
// times in rig time since the run started:
//   stuck@5:x_r           x_r's reading frozen at its present value
//   rail@5:x_r            x_r's reading at the top of its ADC range (open circuit)
//   noise@5:x_r:0.005:0.5 Gaussian noise of 5 mm SD added to x_r for 0.5 s (0 or absent: to the end)
//   nan@5:x_r[:DURATION]  x_r reads not-a-number
//   offset@5:x_r:0.01     x_r's reading steps by +10 mm (SI unit of the channel)
//   overrun@5:25[:2]      25 consecutive reads each stall 2 periods (the loop overruns)
//   supply@5:1e6          the plant's supply pressure drops to 10 bar gauge [Pa]
//   burst@5:p1[:1e-6]     chamber 1 opens to tank through K = 1e-6 m^3/s/sqrt(Pa) (burst pipe)
#pragma once

#include <string>
#include <vector>

namespace rigctl {

enum class FaultKind {
  // On the wire (rig-sim); stuck and rail also in the simulated driver.
  kSilence, kDrop, kLate, kException, kStuck, kRail, kHeartbeat, kEmcy, kHold,
  // In the simulated driver of `rigctl run` only.
  kNoise, kNan, kOffset, kOverrun, kSupply, kBurst
};

// Where a kind can be injected.
bool fault_on_wire(FaultKind kind);      // `rigctl rig-sim --fault`
bool fault_in_process(FaultKind kind);   // `rigctl run` with the simulated driver

struct FaultSpec {
  FaultKind kind = FaultKind::kDrop;
  double at_s = 0.0;
  double duration_s = 0.0;  // silence, late, heartbeat, hold, noise, nan; 0 = until the end
  double delay_s = 0.0;     // late
  std::string channel;      // exception, stuck, rail, noise, nan, offset; burst: p1 or p2
  double value = 0.0;       // noise SD, offset [channel SI]; supply pressure [Pa]; burst K [m^3/s/sqrt(Pa)]
  int count = 0;            // overrun: consecutive stalled reads
  int stall_periods = 0;    // overrun: each read stalls this many periods
  int code = 0;             // exception code, or EMCY error code
  int error_register = 0;   // emcy
  std::string text;         // as given, for messages
};

// Throws std::invalid_argument naming the spec and what is wrong.
FaultSpec parse_fault_spec(const std::string& spec);

}  // namespace rigctl
