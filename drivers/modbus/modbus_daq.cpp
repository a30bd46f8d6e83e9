#include "drivers/modbus/modbus_daq.hpp"

#include "rt/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "drivers/modbus/modbus_link.hpp"
#include "drivers/modbus/modbus_write_plan.hpp"

namespace rigctl {

namespace {

constexpr std::size_t kMaxEvents = 256;  // pending events; beyond that they are counted, not kept

int64_t to_ns(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

std::string ms_text(double s) {
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

}  // namespace

// Everything only the I/O thread touches.
class ModbusDaq::Io {
 public:
  explicit Io(const ModbusDaqConfig& c) : link(c.connection) {
    std::vector<ModbusPoint> in, out;
    for (const auto& ch : c.inputs) in.push_back(ch.point);
    for (const auto& ch : c.outputs) out.push_back(ch.point);
    read_plan = plan_reads(in, {c.max_gap, kMaxReadRegisters});
    write_plan = plan_writes(out);
    for (const auto& b : read_plan.blocks) {
      read_buffers.emplace_back(static_cast<std::size_t>(b.count));
      read_states.push_back({describe_request(false, b.type, b.unit_id, b.address, b.count), 0, {}});
    }
    for (const auto& b : write_plan.blocks) {
      write_buffers.emplace_back(static_cast<std::size_t>(b.count));
      write_states.push_back({describe_request(true, RegisterType::kHoldingRegister, b.unit_id, b.address, b.count), 0, {}});
    }
    // Which inputs each block fills, so a cycle decodes without searching.
    inputs_of_block.resize(read_plan.blocks.size());
    for (std::size_t i = 0; i < read_plan.where.size(); ++i) {
      inputs_of_block[static_cast<std::size_t>(read_plan.where[i].block)].push_back(i);
    }
  }

  ModbusLink link;
  ReadPlan read_plan;
  WritePlan write_plan;
  std::vector<std::vector<uint16_t>> read_buffers, write_buffers;
  std::vector<RequestState> read_states, write_states;
  std::vector<std::vector<std::size_t>> inputs_of_block;
  InputSnapshot current;  // newest value and acquisition time of every input

  bool answered = false;       // the open connection has answered at least once
  bool ever_answered = false;  // some connection has (later ones are reconnects)
  bool connect_failing = false;  // a connect-failure episode is under way (logged once)
  int64_t next_connect_ns = 0;
  int64_t last_answer_ns = 0;  // last reply of any kind (data or exception)
};

namespace {

ModbusDaqConfig validated(ModbusDaqConfig c) {
  validate(c);
  return c;
}

}  // namespace

ModbusDaq::OutputCommand ModbusDaq::safe_command(const ModbusDaqConfig& c) {
  OutputCommand safe;
  for (std::size_t i = 0; i < c.outputs.size(); ++i) safe.value[i] = c.outputs[i].safe;
  return safe;
}

ModbusDaq::InputSnapshot ModbusDaq::never_read() {
  InputSnapshot s;
  s.value.fill(std::numeric_limits<double>::quiet_NaN());
  return s;
}

ModbusDaq::ModbusDaq(ModbusDaqConfig config)
    : config_(validated(std::move(config))),
      endpoint_(endpoint_name(config_.connection)),
      safe_(safe_command(config_)),
      io_(std::make_unique<Io>(config_)),
      inputs_(never_read()),
      outputs_(safe_),
      latency_(1000, 20000) {  // 1 us bins up to 20 ms; beyond lands in the last bin, max stays exact
  io_->current = never_read();
}

ModbusDaq::~ModbusDaq() { stop(); }

int64_t ModbusDaq::now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void ModbusDaq::start(double first_sample_timeout_s) {
  if (thread_.joinable()) throw std::logic_error("modbus " + endpoint_ + ": already started");
  stop_requested_ = false;
  first_sample_ = false;
  make_safe();  // no stale command from a previous run; the loop is not running yet
  io_->current = never_read();
  outputs_written_ns_ = 0;
  cycles_requested_ = cycles_done_ = lock_step_reads_ = lock_step_since_ns_ = 0;
  thread_ = std::thread([this] { run_io(); });
  if (config_.io_priority > 0) {
    // Set from here, so a refusal (not root, no rtprio limit) is reported
    // like the loop's own: a warning, and the thread runs best effort.
    const int rc = set_fifo_priority(thread_, config_.io_priority);
    if (rc != 0) {
      std::lock_guard lock(mutex_);
      add_event("modbus " + endpoint_ + ": cannot give the I/O thread SCHED_FIFO priority " +
                std::to_string(config_.io_priority) + " (" + std::strerror(rc) + "); it runs best effort");
    }
  }
  std::unique_lock lock(mutex_);
  const bool ok = first_sample_cv_.wait_for(lock, std::chrono::duration<double>(first_sample_timeout_s),
                                            [this] { return first_sample_.load(); });
  if (ok) return;
  const std::string error = last_error_.empty() ? "no reply" : last_error_;
  lock.unlock();
  stop();
  char timeout[32];
  std::snprintf(timeout, sizeof timeout, "%g s", first_sample_timeout_s);
  throw std::runtime_error("modbus " + endpoint_ + ": no complete sample within " + timeout + " (last error: " +
                           error + ")");
}

void ModbusDaq::stop() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard lock(step_mutex_);
    stop_requested_ = true;
  }
  step_cv_.notify_all();
  thread_.join();
}

void ModbusDaq::run_one_cycle() noexcept {
  std::unique_lock lock(step_mutex_);
  const int64_t wanted = ++cycles_requested_;
  step_cv_.notify_all();
  step_cv_.wait(lock, [&] { return cycles_done_ >= wanted || stop_requested_.load(); });
}

bool ModbusDaq::wait_for_cycle_request() noexcept {
  std::unique_lock lock(step_mutex_);
  step_cv_.wait(lock, [&] { return cycles_requested_ > cycles_done_ || stop_requested_.load(); });
  return !stop_requested_.load();
}

void ModbusDaq::cycle_done() noexcept {
  {
    std::lock_guard lock(step_mutex_);
    cycles_done_ = cycles_requested_;
  }
  step_cv_.notify_all();
}

int64_t ModbusDaq::read_inputs(Sample& out, std::size_t first_index, int64_t now) noexcept {
  const std::size_t n = config_.inputs.size();
  if (first_index + n > kMaxInputs) return std::numeric_limits<int64_t>::max();
  // Lock-step: the first read takes start()'s sample, each later one a cycle
  // of its own; an input is fresh when that cycle read it, however long the
  // machine took (the far side's plant waited too).
  if (config_.lock_step && lock_step_reads_++ > 0) {
    lock_step_since_ns_ = now_ns();
    run_one_cycle();
  }
  const InputSnapshot& s = inputs_.read();
  const int64_t max_age = to_ns(config_.max_sample_age_s);
  int64_t oldest = 0;
  bool any_stale = false;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = first_index + i;
    const int64_t t = s.acquired_ns[i];
    const int64_t age = t == 0 ? std::numeric_limits<int64_t>::max() : now - t;
    oldest = std::max(oldest, age);
    const bool old = config_.lock_step ? t == 0 || t < lock_step_since_ns_ : age > max_age;
    const bool bad = old || !std::isfinite(s.value[i]);
    out.value[k] = s.value[i];
    const uint32_t bit = 1u << k;
    out.status = bad ? (out.status | bit) : (out.status & ~bit);
    any_stale = any_stale || bad;
  }
  if (any_stale) stale_samples_.fetch_add(1, std::memory_order_relaxed);
  return oldest;
}

void ModbusDaq::write_outputs(const double* si, std::size_t n) noexcept {
  OutputCommand& c = outputs_.write_slot();
  c = safe_;
  const std::size_t count = std::min(n, config_.outputs.size());
  for (std::size_t i = 0; i < count; ++i) {
    if (std::isnan(si[i])) {
      rejected_[i].fetch_add(1, std::memory_order_relaxed);
    } else {
      c.value[i] = si[i];
    }
  }
  outputs_.publish();
}

void ModbusDaq::make_safe() noexcept {
  outputs_.write_slot() = safe_;
  outputs_.publish();
}

int64_t ModbusDaq::output_age_ns(int64_t now) const noexcept {
  if (config_.outputs.empty()) return 0;
  const int64_t t = outputs_written_ns_.load(std::memory_order_acquire);
  if (t == 0) return std::numeric_limits<int64_t>::max();
  // Lock-step: written by the cycle this tick asked for (or, on the first
  // tick, by start()'s), whatever the clock says.
  if (config_.lock_step) return t >= lock_step_since_ns_ ? 0 : std::numeric_limits<int64_t>::max();
  return now - t;
}

void ModbusDaq::add_event(std::string text) {
  spdlog::warn("{}", text);
  if (events_.size() >= kMaxEvents) {
    ++counters_.events_dropped;
    return;
  }
  events_.push_back(std::move(text));
}

ModbusDaqCounters ModbusDaq::counters() const {
  std::lock_guard lock(mutex_);
  ModbusDaqCounters c = counters_;
  c.connected = connected_.load();
  c.stale_samples = stale_samples_.load(std::memory_order_relaxed);
  c.rejected_outputs = 0;
  for (const auto& r : rejected_) c.rejected_outputs += r.load(std::memory_order_relaxed);
  return c;
}

DistributionSummary ModbusDaq::io_latency() const {
  std::lock_guard lock(mutex_);
  return latency_.summary();
}

DriverDiagnostics ModbusDaq::diagnostics() {
  const ModbusDaqCounters c = counters();
  DriverDiagnostics d;
  d.counters = {{"modbus_connected", c.connected ? 1 : 0},
                {"modbus_cycles", c.cycles},
                {"modbus_cycle_overruns", c.cycle_overruns},
                {"modbus_reads", c.reads},
                {"modbus_writes", c.writes},
                {"modbus_timeouts", c.timeouts},
                {"modbus_exceptions", c.exceptions},
                {"modbus_protocol_errors", c.protocol_errors},
                {"modbus_connection_losses", c.connection_losses},
                {"modbus_connect_failures", c.connect_failures},
                {"modbus_reconnects", c.reconnects},
                {"modbus_stale_samples", c.stale_samples},
                {"modbus_rejected_outputs", c.rejected_outputs},
                {"modbus_saturated_outputs", c.saturated_outputs},
                {"modbus_events_dropped", c.events_dropped}};
  std::lock_guard lock(mutex_);
  // The loop cannot log, so its faults become events here, once per report.
  if (c.stale_samples > stale_reported_) {
    d.events.push_back("modbus " + endpoint_ + ": " + std::to_string(c.stale_samples - stale_reported_) +
                       " samples with stale inputs (older than " + ms_text(config_.max_sample_age_s) + ")");
    stale_reported_ = c.stale_samples;
  }
  for (std::size_t i = 0; i < config_.outputs.size(); ++i) {
    const int64_t r = rejected_[i].load(std::memory_order_relaxed);
    if (r > rejected_reported_[i]) {
      d.events.push_back("modbus " + endpoint_ + ": output " + config_.outputs[i].name + ": " +
                         std::to_string(r - rejected_reported_[i]) + " NaN commands replaced by the safe value");
      rejected_reported_[i] = r;
    }
  }
  d.events.insert(d.events.end(), events_.begin(), events_.end());
  events_.clear();
  return d;
}

// ---------------------------------------------------------------------------
// The I/O thread

void ModbusDaq::run_io() noexcept {
  Io& io = *io_;
  const ModbusConnection& k = config_.connection;
  const std::string prefix = "modbus " + endpoint_ + ": ";
  const int64_t period = to_ns(config_.poll_period_s);
  const int64_t reconnect = to_ns(k.reconnect_interval_s);

  // A connection counts as working from its first answer on: a server that
  // accepts and closes at once (or never answers) is a failed connect,
  // logged once per episode, not a flapping "reconnected / lost" pair.
  auto lose_connection = [&](const std::string& reason) {
    io.link.close();
    connected_ = false;
    io.next_connect_ns = now_ns() + reconnect;
    std::lock_guard lock(mutex_);
    if (!io.answered) {
      ++counters_.connect_failures;
      last_error_ = "connection failed before any reply: " + reason;
      if (!io.connect_failing) add_event(prefix + last_error_ + " (retrying every " + ms_text(k.reconnect_interval_s) + ")");
      io.connect_failing = true;
      return;
    }
    io.answered = false;
    ++counters_.connection_losses;
    last_error_ = "connection lost: " + reason;
    add_event(prefix + "connection lost (" + reason + "); reconnecting every " + ms_text(k.reconnect_interval_s));
  };

  auto try_connect = [&] {
    const int error = io.link.open();
    const int64_t now = now_ns();
    std::lock_guard lock(mutex_);
    if (error != 0) {
      ++counters_.connect_failures;
      last_error_ = "connect failed: " + modbus_error_text(error);
      if (!io.connect_failing) add_event(prefix + last_error_ + " (retrying every " + ms_text(k.reconnect_interval_s) + ")");
      io.connect_failing = true;
      io.next_connect_ns = now + reconnect;
      return;
    }
    io.last_answer_ns = now;
    connected_ = true;
  };

  auto answered = [&] {
    io.last_answer_ns = now_ns();
    if (io.answered) return;
    io.answered = true;
    io.connect_failing = false;
    std::lock_guard lock(mutex_);
    if (io.ever_answered) {
      ++counters_.reconnects;
      add_event(prefix + "reconnected");
    }
    io.ever_answered = true;
  };

  // Bookkeeping of one request's result. Returns false when the cycle must
  // end here (anything but an exception response: the link is suspect).
  auto account = [&](RequestState& st, const ModbusResult& r) -> bool {
    if (r.ok() || r.kind == ModbusErrorKind::kException) answered();
    if (r.ok()) {
      if (st.failures > 0) {
        std::lock_guard lock(mutex_);
        add_event(prefix + st.what + " works again after " + std::to_string(st.failures) +
                  (st.failures == 1 ? " failure" : " failures"));
      }
      st.failures = 0;
      st.logged.clear();
      return true;
    }
    std::string text;
    switch (r.kind) {
      case ModbusErrorKind::kTimeout: text = "timeout (no reply within " + ms_text(k.response_timeout_s) + ")"; break;
      case ModbusErrorKind::kException: text = "exception '" + modbus_error_text(r.error) + "'"; break;
      case ModbusErrorKind::kProtocol: text = "bad reply '" + modbus_error_text(r.error) + "'"; break;
      default: text = "link error '" + modbus_error_text(r.error) + "'"; break;
    }
    text += " " + st.what;
    {
      std::lock_guard lock(mutex_);
      if (r.kind == ModbusErrorKind::kTimeout) ++counters_.timeouts;
      if (r.kind == ModbusErrorKind::kException) ++counters_.exceptions;
      if (r.kind == ModbusErrorKind::kProtocol) ++counters_.protocol_errors;
      last_error_ = text;
      // Once per episode and error: alternating errors (a late reply gives
      // a timeout, then a mismatched reply) must not log every cycle.
      if (std::find(st.logged.begin(), st.logged.end(), r.error) == st.logged.end()) {
        st.logged.push_back(r.error);
        add_event(prefix + text);
      }
    }
    ++st.failures;
    if (r.kind == ModbusErrorKind::kException) return true;
    if (r.kind == ModbusErrorKind::kLink) {
      lose_connection(modbus_error_text(r.error));
    } else {
      io.link.drain();  // a late reply must not be taken for the next request's
      // Silent for a whole reconnect interval: assume a half-open TCP
      // connection (device rebooted, cable moved) and open a new one.
      if (k.transport == ModbusTransport::kTcp && now_ns() - io.last_answer_ns > reconnect) {
        lose_connection("no reply for " + ms_text(k.reconnect_interval_s));
      }
    }
    return false;
  };

  auto write_blocks = [&](const OutputCommand& cmd) -> bool {
    int64_t saturated = 0;
    for (std::size_t i = 0; i < config_.outputs.size(); ++i) {
      const ModbusChannel& ch = config_.outputs[i];
      const PointLocation& at = io.write_plan.where[i];
      uint16_t* regs = io.write_buffers[static_cast<std::size_t>(at.block)].data() + at.offset;
      EncodeStatus st = encode_registers(ch.calibration.to_raw(cmd.value[i]), ch.point.format, ch.point.order, regs);
      if (st == EncodeStatus::kRejected) {  // cannot happen for finite commands; belt and braces
        st = encode_registers(ch.calibration.to_raw(ch.safe), ch.point.format, ch.point.order, regs);
      }
      if (st == EncodeStatus::kSaturated) ++saturated;
    }
    if (saturated > 0) {
      std::lock_guard lock(mutex_);
      counters_.saturated_outputs += saturated;
    }
    bool ok = true;
    for (std::size_t b = 0; b < io.write_plan.blocks.size(); ++b) {
      const ModbusResult r = io.link.write(io.write_plan.blocks[b], io.write_buffers[b].data());
      if (r.ok()) {
        std::lock_guard lock(mutex_);
        ++counters_.writes;
      }
      if (!account(io.write_states[b], r)) return false;
      ok = ok && r.ok();
    }
    if (ok) outputs_written_ns_.store(now_ns(), std::memory_order_release);
    return ok;
  };

  auto cycle = [&] {
    const int64_t t0 = now_ns();
    // Lock-step: the previous tick's command goes out before the inputs are
    // read, so the far side steps its plant with it before it answers.
    const bool first_sample_was = first_sample_.load();
    bool ok = !config_.lock_step || !first_sample_was || write_blocks(outputs_.read());
    if (!ok) return;
    bool go_on = true;
    for (std::size_t b = 0; b < io.read_plan.blocks.size() && go_on; ++b) {
      const int64_t sent = now_ns();
      const ModbusResult r = io.link.read(io.read_plan.blocks[b], io.read_buffers[b].data());
      if (r.ok()) {
        for (std::size_t i : io.inputs_of_block[b]) {
          const ModbusChannel& ch = config_.inputs[i];
          const uint16_t* regs = io.read_buffers[b].data() + io.read_plan.where[i].offset;
          io.current.value[i] = ch.calibration.to_si(decode_registers(regs, ch.point.format, ch.point.order));
          io.current.acquired_ns[i] = sent;
        }
        std::lock_guard lock(mutex_);
        ++counters_.reads;
      }
      go_on = account(io.read_states[b], r);
      ok = ok && r.ok();
    }
    inputs_.write_slot() = io.current;
    inputs_.publish();
    if (!first_sample_) {
      bool all = true;
      for (std::size_t i = 0; i < config_.inputs.size(); ++i) all = all && io.current.acquired_ns[i] != 0;
      if (all && go_on) {
        std::lock_guard lock(mutex_);
        first_sample_ = true;
        first_sample_cv_.notify_all();
      }
    }
    if (!go_on) return;
    if (!config_.lock_step || !first_sample_was) ok = write_blocks(outputs_.read()) && ok;
    if (!ok) return;
    const int64_t took = now_ns() - t0;
    std::lock_guard lock(mutex_);
    ++counters_.cycles;
    latency_.record(took);
  };

  int64_t next = now_ns();
  while (!stop_requested_.load()) {
    // Lock-step: once the first sample is in, a cycle only when the loop asks.
    const bool requested = config_.lock_step && first_sample_.load();
    if (requested && !wait_for_cycle_request()) break;
    if (!io.link.is_open() && now_ns() >= io.next_connect_ns) try_connect();
    const bool ran = io.link.is_open();
    if (ran) cycle();
    if (requested) {
      cycle_done();
      continue;
    }
    next += period;
    const int64_t now = now_ns();
    if (now > next) {
      // Overran: keep the grid's phase and skip the periods already missed
      // (as the loop's skip policy does) rather than polling back to back.
      if (ran) {
        std::lock_guard lock(mutex_);
        ++counters_.cycle_overruns;
      }
      next += (now - next) / period * period + period;
    }
    const timespec ts{static_cast<time_t>(next / 1000000000LL), static_cast<long>(next % 1000000000LL)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }

  // Last act: the outputs' safe values, one attempt.
  if (io.link.is_open() && !config_.outputs.empty()) write_blocks(safe_);
  io.link.close();
  connected_ = false;
}

}  // namespace rigctl
