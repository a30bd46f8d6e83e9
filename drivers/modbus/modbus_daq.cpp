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

#include "drivers/modbus/modbus_daq_io.hpp"

namespace rigctl {

namespace {

constexpr std::size_t kMaxEvents = 256;  // pending events; beyond that they are counted, not kept

using modbus_daq_detail::ms_text;
using modbus_daq_detail::to_ns;

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
      io_(std::make_unique<Io>(*this)),
      inputs_(never_read()),
      outputs_(safe_),
      latency_(1000, 20000) {  // 1 us bins up to 20 ms; beyond lands in the last bin, max stays exact
  io_->forget_inputs(never_read());
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
  io_->forget_inputs(never_read());
  outputs_written_ns_ = 0;
  cycles_requested_ = cycles_done_ = lock_step_reads_ = lock_step_since_ns_ = 0;
  thread_ = std::thread([this] { io_->run(); });
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

}  // namespace rigctl
