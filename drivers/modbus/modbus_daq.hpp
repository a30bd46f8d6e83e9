// The client side of the Modbus DAQ module: the rig's analogue inputs (LVDTs,
// velocity transducers, pressure transducers, load cell) and the servovalve
// current command, in SI units. Not a Driver itself: the rig's hardware
// driver composes it with the CANopen valve.
//
// Thread model. Modbus is blocking request/response I/O; a lost reply costs a
// whole response timeout. So the loop never talks Modbus: an I/O thread owns
// the libmodbus context and, every poll_period_s,
//   1. reads the planned blocks (plan_reads), decodes and calibrates each
//      input to SI and stamps it with the CLOCK_MONOTONIC time its request
//      was sent (the reading is at least that fresh, so ages are never
//      under-estimated);
//   2. publishes the inputs to the loop through a wait-free triple buffer;
//   3. writes the newest outputs the loop posted (another triple buffer),
//      calibrated and encoded, contiguous registers in one request.
// The loop's read_inputs()/write_outputs() only touch the triple buffers and
// a few relaxed atomics: no lock, no allocation, no system call, whatever the
// I/O thread is doing. An input that did not arrive simply ages; read_inputs()
// flags it stale in Sample::status once older than max_sample_age_s, and the
// loop's limit check then makes the rig safe.
//
// Failures. A timeout or a mismatched reply ends the cycle (the next request
// would most likely fail too); the line is then drained for one response
// timeout so a late reply cannot be taken for a later request's (see
// ModbusLink::drain). An exception response only fails its own block: its
// inputs go stale, the other blocks are still read.
// A link error (reset, closed, serial I/O error) closes the connection; the
// I/O thread reconnects every reconnect_interval_s without a restart. A TCP
// connection that has answered nothing for reconnect_interval_s is also
// re-opened (a half-open connection after a device reboot never recovers by
// itself). Everything is counted; each failure episode of a request is logged
// once, with the register range, unit and libmodbus's text, and once more when
// it recovers.
//
// Output latency: up to one poll period plus the reads, because the I/O
// thread runs on its own clock rather than being woken by the loop (waking it
// would need a system call on the real-time path). Failed writes make
// output_age_ns() grow, the outputs' counterpart of stale inputs.
//
// Priority: the inputs are only as fresh as the I/O thread is punctual, so
// config io_priority gives it SCHED_FIFO (just below the loop's); mlockall of
// the loop's set-up covers it. Measured on the 2-core VM under load (two busy
// loops plus other builds): ticks with a stale input went from 0.7-3 % at
// normal priority to 0.03-0.3 % (2 ms timeout, 7.5 ms maximum age).
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "rt/driver.hpp"
#include "drivers/modbus/modbus_daq_config.hpp"
#include "drivers/modbus/modbus_triple_buffer.hpp"
#include "rt/histogram.hpp"
#include "rt/sample.hpp"
#include "rt/timing_summary.hpp"

namespace rigctl {

struct ModbusDaqCounters {
  int64_t cycles = 0;             // I/O cycles completed without error
  int64_t cycle_overruns = 0;     // cycles that ended after the next cycle was due
  int64_t reads = 0;              // successful read requests
  int64_t writes = 0;             // successful write requests
  int64_t timeouts = 0;           // requests with no reply within the response timeout
  int64_t exceptions = 0;         // Modbus exception responses
  int64_t protocol_errors = 0;    // replies not matching the request (late, bad CRC, ...)
  int64_t connection_losses = 0;  // working connections closed after a link error or silence
  int64_t connect_failures = 0;   // connection attempts that failed or closed before any reply
  int64_t reconnects = 0;         // connections that answered after a loss (not the first)
  int64_t stale_samples = 0;      // read_inputs() calls that flagged at least one input
  int64_t rejected_outputs = 0;   // NaN output commands replaced by the channel's safe value
  int64_t saturated_outputs = 0;  // output values clamped to the register format's range
  int64_t events_dropped = 0;     // events lost because the event list was full
  bool connected = false;
};

class ModbusDaq {
 public:
  // Validates (std::invalid_argument) and plans the requests. Opens nothing.
  explicit ModbusDaq(ModbusDaqConfig config);
  ~ModbusDaq();  // stop()
  ModbusDaq(const ModbusDaq&) = delete;
  ModbusDaq& operator=(const ModbusDaq&) = delete;

  const ModbusDaqConfig& config() const noexcept { return config_; }
  std::size_t input_count() const noexcept { return config_.inputs.size(); }
  std::size_t output_count() const noexcept { return config_.outputs.size(); }
  const std::string& endpoint() const noexcept { return endpoint_; }

  // Starts the I/O thread and waits until every input has been read once.
  // Throws std::runtime_error naming the endpoint and the last error when
  // that does not happen within first_sample_timeout_s (the thread is then
  // stopped again). Until the loop posts outputs, the safe values are written.
  void start(double first_sample_timeout_s);

  // Stops the I/O thread; its last act is writing every output's safe value
  // (one attempt, if connected). Closes the connection. Idempotent.
  void stop();

  // --- Real-time path: call from the loop thread only (one reader, one writer).

  // Copies the newest SI inputs to out.value[first_index + i] and sets
  // out.status bit (first_index + i) for each input that is stale (acquired
  // more than max_sample_age_s before now_ns), never read, or not finite;
  // clears it otherwise. now_ns is CLOCK_MONOTONIC (now_ns()). Returns the
  // age of the oldest input in ns (INT64_MAX while one was never read).
  // Requires first_index + input_count() <= kMaxInputs (else nothing is touched).
  // In lock-step (ModbusDaqConfig::lock_step) every call after the first
  // runs one I/O cycle and waits for it (it locks and waits then), and an
  // input is stale when that cycle did not read it (no wall-clock age).
  int64_t read_inputs(Sample& out, std::size_t first_index, int64_t now_ns) noexcept;

  // Posts the outputs (SI, output order; n <= output_count(), missing ones
  // keep the safe value). A NaN is a fault: that output gets its safe value
  // and the rejection is counted.
  void write_outputs(const double* si, std::size_t n) noexcept;

  // Posts every output's safe value (the valve null). Same thread as write_outputs.
  void make_safe() noexcept;

  // Time since every output was last written successfully (INT64_MAX before
  // the first write; 0 without outputs). Inputs carry their own staleness;
  // this is the outputs' equivalent: while writes fail (exception, timeout,
  // lost link) the amplifier holds an old command, and the composing driver
  // should fault once this exceeds its limit (e.g. max_sample_age_s).
  int64_t output_age_ns(int64_t now_ns) const noexcept;

  static int64_t now_ns() noexcept;  // CLOCK_MONOTONIC

  // --- Not real-time; any thread.

  // Counters (named modbus_*) and the events since the previous call.
  DriverDiagnostics diagnostics();
  ModbusDaqCounters counters() const;
  // Duration of one complete I/O cycle (all reads and writes), for the run summary.
  DistributionSummary io_latency() const;

 private:
  struct InputSnapshot {
    std::array<double, kMaxInputs> value{};
    std::array<int64_t, kMaxInputs> acquired_ns{};  // 0: never read
  };
  struct OutputCommand {
    std::array<double, kMaxOutputs> value{};
  };
  class Io;  // the I/O thread: its state (libmodbus context, plans, buffers) and steps (modbus_daq_io.hpp)
  static OutputCommand safe_command(const ModbusDaqConfig& config);
  static InputSnapshot never_read();

  // Lock-step: the loop's side asks for one cycle and waits for its end; the
  // I/O thread waits for a request (false: stop requested) and reports its end.
  void run_one_cycle() noexcept;
  bool wait_for_cycle_request() noexcept;
  void cycle_done() noexcept;
  void add_event(std::string text);  // with mutex_ held

  ModbusDaqConfig config_;
  std::string endpoint_;
  OutputCommand safe_;
  std::unique_ptr<Io> io_;

  TripleBuffer<InputSnapshot> inputs_;    // I/O thread -> loop
  TripleBuffer<OutputCommand> outputs_;   // loop -> I/O thread

  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> first_sample_{false};
  std::atomic<bool> connected_{false};
  std::atomic<int64_t> outputs_written_ns_{0};  // end of the last complete successful write; 0: never

  // Lock-step cycles asked for by the loop and completed by the I/O thread.
  std::mutex step_mutex_;
  std::condition_variable step_cv_;
  int64_t cycles_requested_ = 0;
  int64_t cycles_done_ = 0;
  int64_t lock_step_reads_ = 0;      // loop thread only
  int64_t lock_step_since_ns_ = 0;   // when the loop asked for the present cycle (0: start()'s)

  // Loop-side counters (relaxed atomics: the loop must not lock).
  std::atomic<int64_t> stale_samples_{0};
  std::array<std::atomic<int64_t>, kMaxOutputs> rejected_{};
  int64_t stale_reported_ = 0;  // under mutex_: what diagnostics() already reported
  std::array<int64_t, kMaxOutputs> rejected_reported_{};

  // I/O-thread counters, events and latency, read by diagnostics().
  mutable std::mutex mutex_;
  std::condition_variable first_sample_cv_;
  ModbusDaqCounters counters_;
  std::deque<std::string> events_;
  std::string last_error_;
  DurationHistogram latency_;
};

}  // namespace rigctl
