// The one interface between the loop and a rig. The simulated plant, the
// Modbus DAQ and the CANopen valve all sit behind it; the loop cannot tell
// them apart.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "rt/sample.hpp"
#include "rt/timing_summary.hpp"

namespace rigctl {

// What a driver reports about its I/O, off the real-time path.
struct DriverDiagnostics {
  // Running totals, e.g. {"modbus_timeouts", 3}, {"can_malformed_frames", 0}.
  std::vector<std::pair<std::string, int64_t>> counters;
  // Human-readable events since the previous call, each naming what failed,
  // e.g. "modbus: timeout reading input registers 0-7 of unit 1".
  std::vector<std::string> events;
};

class Driver {
 public:
  virtual ~Driver() = default;

  // Names and SI units of what read() fills and write() takes. Fixed after start().
  virtual const ChannelLayout& layout() const = 0;

  // Opens devices, connects, primes the plant. Not real-time; may throw.
  virtual void start() = 0;

  // Real-time path: fills `out` with the latest inputs in SI units, their
  // status bits and the outputs whose actuator is not following. Must not
  // allocate, lock or block beyond the device's own bounded I/O. Returns false
  // when no usable sample could be had this tick.
  virtual bool read(Sample& out) = 0;

  // Real-time path: hands the outputs to the rig.
  virtual void write(const Command& command) = 0;

  // Puts the outputs in their safe state (valve to null). Called on every way
  // out of the loop, including faults; must not throw.
  virtual void make_safe() noexcept = 0;

  // Closes devices. Not real-time.
  virtual void stop() = 0;

  // Counters and new events. Not real-time; safe to call from another thread
  // while the loop runs.
  virtual DriverDiagnostics diagnostics() { return {}; }

  // Why input `input` was first flagged invalid in this run, in words, where
  // the driver knows more than the flag (e.g. "canopen valve node 1:
  // heartbeat lost ..."); empty otherwise. Not real-time; still valid after
  // stop().
  virtual std::string input_fault_cause(std::size_t input) const {
    (void)input;
    return {};
  }

  // Round-trip time of the driver's I/O cycles, for the run summary; count 0
  // when the driver has no wire (the simulated plant).
  virtual DistributionSummary io_latency() const { return {}; }

  // True when time is simulated, so the loop may run faster than real time
  // (--fast) with identical results.
  virtual bool simulated() const { return false; }
};

}  // namespace rigctl
