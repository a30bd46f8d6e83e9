// The Modbus DAQ's I/O thread, step by step (modbus_daq_io.hpp).
#include "drivers/modbus/modbus_daq_io.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <mutex>

namespace rigctl {

using modbus_daq_detail::ms_text;
using modbus_daq_detail::to_ns;

namespace {

// "timeout (no reply within 2 ms) reading input registers 0-7 of unit 1"
std::string failure_text(const ModbusResult& r, const ModbusConnection& k, const std::string& what) {
  std::string text;
  switch (r.kind) {
    case ModbusErrorKind::kTimeout: text = "timeout (no reply within " + ms_text(k.response_timeout_s) + ")"; break;
    case ModbusErrorKind::kException: text = "exception '" + modbus_error_text(r.error) + "'"; break;
    case ModbusErrorKind::kProtocol: text = "bad reply '" + modbus_error_text(r.error) + "'"; break;
    default: text = "link error '" + modbus_error_text(r.error) + "'"; break;
  }
  return text + " " + what;
}

}  // namespace

ModbusDaq::Io::Io(ModbusDaq& daq)
    : daq_(daq),
      config_(daq.config_),
      prefix_("modbus " + daq.endpoint_ + ": "),
      period_ns_(to_ns(config_.poll_period_s)),
      reconnect_ns_(to_ns(config_.connection.reconnect_interval_s)),
      link_(config_.connection) {
  std::vector<ModbusPoint> in, out;
  for (const auto& ch : config_.inputs) in.push_back(ch.point);
  for (const auto& ch : config_.outputs) out.push_back(ch.point);
  read_plan_ = plan_reads(in, {config_.max_gap, kMaxReadRegisters});
  write_plan_ = plan_writes(out);
  for (const auto& b : read_plan_.blocks) {
    read_buffers_.emplace_back(static_cast<std::size_t>(b.count));
    read_states_.push_back({describe_request(false, b.type, b.unit_id, b.address, b.count), 0, {}});
  }
  for (const auto& b : write_plan_.blocks) {
    write_buffers_.emplace_back(static_cast<std::size_t>(b.count));
    write_states_.push_back(
        {describe_request(true, RegisterType::kHoldingRegister, b.unit_id, b.address, b.count), 0, {}});
  }
  // Which inputs each block fills, so a cycle decodes without searching.
  inputs_of_block_.resize(read_plan_.blocks.size());
  for (std::size_t i = 0; i < read_plan_.where.size(); ++i) {
    inputs_of_block_[static_cast<std::size_t>(read_plan_.where[i].block)].push_back(i);
  }
}

void ModbusDaq::Io::run() noexcept {
  int64_t next = now_ns();
  while (!daq_.stop_requested_.load()) {
    // Lock-step: once the first sample is in, a cycle only when the loop asks.
    const bool requested = config_.lock_step && daq_.first_sample_.load();
    if (requested && !daq_.wait_for_cycle_request()) break;
    if (!link_.is_open() && now_ns() >= next_connect_ns_) connect();
    const bool ran = link_.is_open();
    if (ran) cycle();
    if (requested) {
      daq_.cycle_done();
      continue;
    }
    next = next_deadline(next, ran);
    sleep_until(next);
  }
  // Last act: the outputs' safe values, one attempt.
  if (link_.is_open() && !config_.outputs.empty()) write_blocks(daq_.safe_);
  link_.close();
  daq_.connected_ = false;
}

// ---------------------------------------------------------------------------
// The connection

void ModbusDaq::Io::connect() {
  const int error = link_.open();
  const int64_t now = now_ns();
  std::lock_guard lock(daq_.mutex_);
  if (error != 0) {
    note_connect_failure("connect failed: " + modbus_error_text(error));
    next_connect_ns_ = now + reconnect_ns_;
    return;
  }
  last_answer_ns_ = now;
  daq_.connected_ = true;
}

void ModbusDaq::Io::note_connect_failure(const std::string& error) {
  ++daq_.counters_.connect_failures;
  daq_.last_error_ = error;
  if (!connect_failing_) {
    daq_.add_event(prefix_ + daq_.last_error_ + " (retrying every " + ms_text(config_.connection.reconnect_interval_s) +
                   ")");
  }
  connect_failing_ = true;
}

void ModbusDaq::Io::lose_connection(const std::string& reason) {
  link_.close();
  daq_.connected_ = false;
  next_connect_ns_ = now_ns() + reconnect_ns_;
  std::lock_guard lock(daq_.mutex_);
  if (!answered_) {
    note_connect_failure("connection failed before any reply: " + reason);
    return;
  }
  answered_ = false;
  ++daq_.counters_.connection_losses;
  daq_.last_error_ = "connection lost: " + reason;
  daq_.add_event(prefix_ + "connection lost (" + reason + "); reconnecting every " +
                 ms_text(config_.connection.reconnect_interval_s));
}

void ModbusDaq::Io::note_answer() {
  last_answer_ns_ = now_ns();
  if (answered_) return;
  answered_ = true;
  connect_failing_ = false;
  std::lock_guard lock(daq_.mutex_);
  if (ever_answered_) {
    ++daq_.counters_.reconnects;
    daq_.add_event(prefix_ + "reconnected");
  }
  ever_answered_ = true;
}

// ---------------------------------------------------------------------------
// One request's result

bool ModbusDaq::Io::account(RequestState& st, const ModbusResult& r) {
  if (r.ok() || r.kind == ModbusErrorKind::kException) note_answer();
  if (r.ok()) {
    if (st.failures > 0) {
      std::lock_guard lock(daq_.mutex_);
      daq_.add_event(prefix_ + st.what + " works again after " + std::to_string(st.failures) +
                     (st.failures == 1 ? " failure" : " failures"));
    }
    st.failures = 0;
    st.logged.clear();
    return true;
  }
  note_failure(st, r);
  return recover_after_failure(r);
}

void ModbusDaq::Io::note_failure(RequestState& st, const ModbusResult& r) {
  const std::string text = failure_text(r, config_.connection, st.what);
  {
    std::lock_guard lock(daq_.mutex_);
    if (r.kind == ModbusErrorKind::kTimeout) ++daq_.counters_.timeouts;
    if (r.kind == ModbusErrorKind::kException) ++daq_.counters_.exceptions;
    if (r.kind == ModbusErrorKind::kProtocol) ++daq_.counters_.protocol_errors;
    daq_.last_error_ = text;
    // Once per episode and error: alternating errors (a late reply gives
    // a timeout, then a mismatched reply) must not log every cycle.
    if (std::find(st.logged.begin(), st.logged.end(), r.error) == st.logged.end()) {
      st.logged.push_back(r.error);
      daq_.add_event(prefix_ + text);
    }
  }
  ++st.failures;
}

// An exception response only fails its own request (true: the cycle goes
// on); anything else leaves the link suspect.
bool ModbusDaq::Io::recover_after_failure(const ModbusResult& r) {
  if (r.kind == ModbusErrorKind::kException) return true;
  const ModbusConnection& k = config_.connection;
  if (r.kind == ModbusErrorKind::kLink) {
    lose_connection(modbus_error_text(r.error));
  } else {
    link_.drain();  // a late reply must not be taken for the next request's
    // Silent for a whole reconnect interval: assume a half-open TCP
    // connection (device rebooted, cable moved) and open a new one.
    if (k.transport == ModbusTransport::kTcp && now_ns() - last_answer_ns_ > reconnect_ns_) {
      lose_connection("no reply for " + ms_text(k.reconnect_interval_s));
    }
  }
  return false;
}

// ---------------------------------------------------------------------------
// One cycle

void ModbusDaq::Io::cycle() {
  const int64_t t0 = now_ns();
  // Lock-step: the previous tick's command goes out before the inputs are
  // read, so the far side steps its plant with it before it answers.
  const bool outputs_first = config_.lock_step && daq_.first_sample_.load();
  if (outputs_first && !write_blocks(daq_.outputs_.read())) return;
  const ReadOutcome read = read_blocks();
  publish_inputs(read.go_on);
  if (!read.go_on) return;
  const bool wrote = outputs_first || write_blocks(daq_.outputs_.read());
  if (!(wrote && read.all_ok)) return;
  const int64_t took = now_ns() - t0;
  std::lock_guard lock(daq_.mutex_);
  ++daq_.counters_.cycles;
  daq_.latency_.record(took);
}

ModbusDaq::Io::ReadOutcome ModbusDaq::Io::read_blocks() {
  ReadOutcome outcome;
  for (std::size_t b = 0; b < read_plan_.blocks.size() && outcome.go_on; ++b) {
    const int64_t sent = now_ns();
    const ModbusResult r = link_.read(read_plan_.blocks[b], read_buffers_[b].data());
    if (r.ok()) take_block(b, sent);
    outcome.go_on = account(read_states_[b], r);
    outcome.all_ok = outcome.all_ok && r.ok();
  }
  return outcome;
}

// Decodes and calibrates the block's inputs, stamped with the time the
// request was sent (the reading is at least that fresh).
void ModbusDaq::Io::take_block(std::size_t b, int64_t sent_ns) {
  for (std::size_t i : inputs_of_block_[b]) {
    const ModbusChannel& ch = config_.inputs[i];
    const uint16_t* regs = read_buffers_[b].data() + read_plan_.where[i].offset;
    current_.value[i] = ch.calibration.to_si(decode_registers(regs, ch.point.format, ch.point.order));
    current_.acquired_ns[i] = sent_ns;
  }
  count(&ModbusDaqCounters::reads);
}

// Hands the inputs to the loop; the first complete sample releases start().
void ModbusDaq::Io::publish_inputs(bool go_on) {
  daq_.inputs_.write_slot() = current_;
  daq_.inputs_.publish();
  if (daq_.first_sample_ || !every_input_read() || !go_on) return;
  std::lock_guard lock(daq_.mutex_);
  daq_.first_sample_ = true;
  daq_.first_sample_cv_.notify_all();
}

bool ModbusDaq::Io::every_input_read() const {
  for (std::size_t i = 0; i < config_.inputs.size(); ++i) {
    if (current_.acquired_ns[i] == 0) return false;
  }
  return true;
}

bool ModbusDaq::Io::write_blocks(const OutputCommand& cmd) {
  encode_outputs(cmd);
  bool ok = true;
  for (std::size_t b = 0; b < write_plan_.blocks.size(); ++b) {
    const ModbusResult r = link_.write(write_plan_.blocks[b], write_buffers_[b].data());
    if (r.ok()) count(&ModbusDaqCounters::writes);
    if (!account(write_states_[b], r)) return false;
    ok = ok && r.ok();
  }
  if (ok) daq_.outputs_written_ns_.store(now_ns(), std::memory_order_release);
  return ok;
}

// Calibrates and encodes every output into its block's registers; counts
// the values clamped to the register format's range.
void ModbusDaq::Io::encode_outputs(const OutputCommand& cmd) {
  int64_t saturated = 0;
  for (std::size_t i = 0; i < config_.outputs.size(); ++i) {
    const ModbusChannel& ch = config_.outputs[i];
    const PointLocation& at = write_plan_.where[i];
    uint16_t* regs = write_buffers_[static_cast<std::size_t>(at.block)].data() + at.offset;
    EncodeStatus st = encode_registers(ch.calibration.to_raw(cmd.value[i]), ch.point.format, ch.point.order, regs);
    if (st == EncodeStatus::kRejected) {  // cannot happen for finite commands; belt and braces
      st = encode_registers(ch.calibration.to_raw(ch.safe), ch.point.format, ch.point.order, regs);
    }
    if (st == EncodeStatus::kSaturated) ++saturated;
  }
  if (saturated > 0) count(&ModbusDaqCounters::saturated_outputs, saturated);
}

// ---------------------------------------------------------------------------
// Pacing

int64_t ModbusDaq::Io::next_deadline(int64_t next, bool ran) {
  next += period_ns_;
  const int64_t now = now_ns();
  if (now > next) {
    // Overran: keep the grid's phase and skip the periods already missed
    // (as the loop's skip policy does) rather than polling back to back.
    if (ran) count(&ModbusDaqCounters::cycle_overruns);
    next += (now - next) / period_ns_ * period_ns_ + period_ns_;
  }
  return next;
}

void ModbusDaq::Io::sleep_until(int64_t deadline_ns) {
  const timespec ts{static_cast<time_t>(deadline_ns / 1000000000LL), static_cast<long>(deadline_ns % 1000000000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void ModbusDaq::Io::count(int64_t ModbusDaqCounters::*counter, int64_t n) {
  std::lock_guard lock(daq_.mutex_);
  daq_.counters_.*counter += n;
}

}  // namespace rigctl
