// The Modbus DAQ's I/O thread (the thread model and the failure policy are
// in modbus_daq.hpp): a small class whose run() is the thread's body, a loop
// over named steps: connect when due, one cycle (read the planned blocks,
// publish the inputs, write the newest outputs), wait for the next period;
// the safe outputs last. Private to the DAQ: included by modbus_daq.cpp and
// modbus_daq_io.cpp only.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "drivers/modbus/modbus_daq.hpp"
#include "drivers/modbus/modbus_link.hpp"
#include "drivers/modbus/modbus_write_plan.hpp"

namespace rigctl {

namespace modbus_daq_detail {

inline int64_t to_ns(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

inline std::string ms_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g ms", s * 1e3);
  return buf;
}

// Failure bookkeeping of one request (a read or write block), so that a
// failure episode is logged once, not 400 times a second.
struct RequestState {
  std::string what;  // "reading input registers 0-7 of unit 1"
  int64_t failures = 0;  // in a row
  std::vector<int> logged;  // errors already logged in this failure episode
};

}  // namespace modbus_daq_detail

// Everything only the I/O thread touches, and its steps. What it shares with
// the loop and with diagnostics() lives in the ModbusDaq (triple buffers,
// atomics, the counters under its mutex).
class ModbusDaq::Io {
 public:
  // Plans the requests from daq's config (already validated).
  explicit Io(ModbusDaq& daq);

  // The thread's body: runs until the DAQ's stop is requested, then writes
  // the safe outputs (one attempt) and closes the connection.
  void run() noexcept;

  // Forgets every input (start() does, before a new thread runs).
  void forget_inputs(const InputSnapshot& never_read) { current_ = never_read; }

 private:
  using RequestState = modbus_daq_detail::RequestState;
  struct ReadOutcome {
    bool all_ok = true;  // every block read
    bool go_on = true;   // the link is fit for the rest of the cycle
  };

  // Connection steps. A connection counts as working from its first answer
  // on: a server that accepts and closes at once (or never answers) is a
  // failed connect, logged once per episode, not a flapping "reconnected /
  // lost" pair.
  void connect();
  void lose_connection(const std::string& reason);
  void note_answer();
  void note_connect_failure(const std::string& error);  // with the DAQ's mutex held

  // One request's result. Returns false when the cycle must end here
  // (anything but an exception response: the link is suspect).
  bool account(RequestState& st, const ModbusResult& r);
  void note_failure(RequestState& st, const ModbusResult& r);
  bool recover_after_failure(const ModbusResult& r);

  // The cycle's steps.
  void cycle();
  ReadOutcome read_blocks();
  void take_block(std::size_t block, int64_t sent_ns);
  void publish_inputs(bool go_on);
  bool every_input_read() const;
  bool write_blocks(const OutputCommand& cmd);
  void encode_outputs(const OutputCommand& cmd);

  // Pacing: the next deadline on the poll grid, and the sleep to it.
  int64_t next_deadline(int64_t next, bool ran);
  static void sleep_until(int64_t deadline_ns);

  void count(int64_t ModbusDaqCounters::*counter, int64_t n = 1);  // takes the DAQ's mutex

  ModbusDaq& daq_;
  const ModbusDaqConfig& config_;
  const std::string prefix_;  // "modbus <endpoint>: "
  const int64_t period_ns_;
  const int64_t reconnect_ns_;

  ModbusLink link_;
  ReadPlan read_plan_;
  WritePlan write_plan_;
  std::vector<std::vector<uint16_t>> read_buffers_, write_buffers_;
  std::vector<RequestState> read_states_, write_states_;
  std::vector<std::vector<std::size_t>> inputs_of_block_;
  InputSnapshot current_;  // newest value and acquisition time of every input

  bool answered_ = false;        // the open connection has answered at least once
  bool ever_answered_ = false;   // some connection has (later ones are reconnects)
  bool connect_failing_ = false;  // a connect-failure episode is under way (logged once)
  int64_t next_connect_ns_ = 0;
  int64_t last_answer_ns_ = 0;  // last reply of any kind (data or exception)
};

}  // namespace rigctl
