// Publisher thread: drains the real-time loop's queue, turns each record into
// LCM messages, publishes them and writes the same bytes into an LCM log.
#include "rt/comms/telemetry_publisher.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rt/comms/event_text.hpp"
#include "rigctl/channels_t.hpp"
#include "rigctl/command_t.hpp"
#include "rigctl/controller_t.hpp"
#include "rigctl/driver_status_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/procedure_t.hpp"
#include "rigctl/state_t.hpp"
#include "rigctl/timing_t.hpp"

namespace rigctl {

namespace {

using Clock = std::chrono::steady_clock;

// A crash (or SIGKILL) of the process loses what is still in stdio's buffer
// (and in the queue the thread has not drained yet). Flushing the buffer to
// the kernel this often bounds the first part to 250 ms of telemetry; a
// flush is one write(2) of at most a few kB, four a second cost nothing.
// (It is not an fsync: a power cut may lose more. SAFETY.md has the
// measured loss.)
constexpr auto kLogFlushInterval = std::chrono::milliseconds(250);
constexpr auto kIdleSleep = std::chrono::milliseconds(1);
constexpr auto kDriverStatusInterval = std::chrono::seconds(1);  // driver counters: once a second, as documented

// Names, units and values of a layout's channels into a message's arrays;
// returns the count. The constructor made sure the layout fits the record.
template <std::size_t N>
int16_t fill_channels(const std::vector<ChannelInfo>& channels, const std::array<double, N>& values,
                      std::vector<std::string>& names, std::vector<std::string>& units, std::vector<double>& out) {
  for (std::size_t i = 0; i < channels.size(); ++i) {
    names.push_back(channels[i].name);
    units.push_back(channels[i].unit);
    out.push_back(values[i]);
  }
  return static_cast<int16_t>(channels.size());
}

// The one place a message is encoded, published, logged and handed to the taps
// (the Foxglove server), so that the log and the taps hold exactly the bytes
// that went onto the bus. Returns 0, or the errno of a failed log write (the
// caller reports it; the loop is never affected).
template <typename Msg>
int emit(lcm::LCM& lcm, lcm::LogFile* log, const std::vector<TelemetryTap*>& taps, const std::string& channel,
         int64_t utime, const Msg& msg) {
  const int size = msg.getEncodedSize();
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  if (msg.encode(buf.data(), 0, size) != size) {
    spdlog::error("telemetry: encoding a message for {} failed", channel);
    return 0;
  }
  if (lcm.publish(channel, buf.data(), static_cast<unsigned int>(size)) != 0) {
    // A broken bus fails on every tick: warn on the first and every 10000th.
    static std::atomic<int64_t> failures{0};
    if (failures.fetch_add(1) % 10000 == 0) spdlog::warn("telemetry: publish on {} failed", channel);
  }
  int result = 0;
  if (log != nullptr) {
    lcm::LogEvent ev{};
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = size;
    ev.data = buf.data();
    errno = 0;
    if (log->writeEvent(&ev) != 0) result = errno != 0 ? errno : EIO;
  }
  for (TelemetryTap* tap : taps) tap->on_message(channel, utime, buf.data(), buf.size());
  return result;
}

// The tick's steps as arrays in the timing message (publisher thread: it may allocate).
void fill_stages(const TickStageSummary& st, rigctl::timing_t& m) {
  m.stage_count = static_cast<int8_t>(kTickStageCount);
  m.stage_name.clear();
  m.stage_max_ns.assign(st.max_ns.begin(), st.max_ns.end());
  m.stage_mean_ns.assign(st.mean_ns.begin(), st.mean_ns.end());
  m.slowest_tick_stage_ns.assign(st.slowest_tick_ns.begin(), st.slowest_tick_ns.end());
  for (std::size_t i = 0; i < kTickStageCount; ++i) m.stage_name.emplace_back(to_string(static_cast<TickStage>(i)));
  m.slowest_tick = st.slowest_tick;
}

}  // namespace

TelemetryPublisher::TelemetryPublisher(TelemetryMeta meta, const std::string& lcm_url,
                                       const std::string& log_path, std::size_t queue_capacity)
    : meta_(std::move(meta)), channels_(meta_.channel_prefix), queue_(queue_capacity, meta_.queue_policy) {
  // The record has fixed-size arrays: refuse a layout that would be cut short
  // in the messages rather than silently drop channels.
  auto check_size = [](std::size_t n, std::size_t max, const char* what) {
    if (n > max) {
      throw std::runtime_error("telemetry: " + std::to_string(n) + " " + what + ", at most " + std::to_string(max) +
                               " fit in a telemetry record");
    }
  };
  check_size(meta_.layout.inputs.size(), kMaxInputs, "inputs");
  check_size(meta_.layout.outputs.size(), kMaxOutputs, "outputs");
  check_size(meta_.term_names.size(), kMaxControllerTerms, "controller terms");
  check_size(meta_.more_setpoint_names.size() + 1, kMaxChannels, "control channels");
  // An empty URL would make LCM fall back to its default multicast group:
  // never do that by accident.
  if (lcm_url.empty()) throw std::runtime_error("telemetry: no LCM URL given (e.g. memq:// or udpm://...)");
  lcm_ = std::make_unique<lcm::LCM>(lcm_url);
  if (!lcm_->good()) throw std::runtime_error("telemetry: cannot open LCM URL '" + lcm_url + "'");
  if (!log_path.empty()) {
    const std::filesystem::path parent = std::filesystem::path(log_path).parent_path();
    std::error_code ec;
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    if (ec) {
      throw std::runtime_error("telemetry: cannot create the directory of log '" + log_path + "': " + ec.message());
    }
    log_ = std::make_unique<lcm::LogFile>(log_path, "w");
    if (!log_->good()) {
      const int err = errno;
      throw std::runtime_error("telemetry: cannot open log '" + log_path + "' for writing: " + std::strerror(err));
    }
  }
}

TelemetryPublisher::~TelemetryPublisher() { stop(); }

bool TelemetryPublisher::push(const TelemetryRecord& record) noexcept { return queue_.push(record); }

void TelemetryPublisher::set_diagnostics_source(std::function<DriverDiagnostics()> source, std::string driver_name) {
  diagnostics_ = std::move(source);
  driver_name_ = std::move(driver_name);
}

void TelemetryPublisher::publish_driver_status() {
  if (!diagnostics_) return;
  DriverDiagnostics d = diagnostics_();
  if (d.counters.empty() && d.events.empty()) return;
  rigctl::driver_status_t m;
  m.utime = meta_.start_utime + last_t_ns_ / 1000;
  m.driver = driver_name_;
  for (auto& [name, value] : d.counters) {
    m.counter_names.push_back(std::move(name));
    m.counters.push_back(value);
  }
  m.num_counters = static_cast<int16_t>(m.counters.size());
  m.events = std::move(d.events);
  m.num_events = static_cast<int16_t>(m.events.size());
  note_log_result(emit(*lcm_, log_.get(), taps_, channels_.driver, m.utime, m));
}

void TelemetryPublisher::start() {
  if (thread_.joinable()) return;
  running_.store(true);
  queue_.set_consumer_running(true);
  thread_ = std::thread([this] { thread_main(); });
}

void TelemetryPublisher::stop() {
  if (stopped_) return;  // the destructor calls it again
  stopped_ = true;
  queue_.set_consumer_running(false);
  running_.store(false);
  if (thread_.joinable()) thread_.join();
  // Whatever the loop pushed before stop() still goes out (also when the
  // thread was never started).
  TelemetryRecord record;
  while (queue_.pop(record)) publish_record(record);
  publish_driver_status();
  publish_reports();
  flush_log();
  log_.reset();  // lcm_eventlog_destroy flushes and closes the file
}

lcm::LCM& TelemetryPublisher::lcm() { return *lcm_; }

void TelemetryPublisher::flush_log() {
  if (!log_) return;
  errno = 0;
  if (std::fflush(log_->getFilePtr()) != 0) note_log_result(errno != 0 ? errno : EIO);
}

// A full disk shows here (usually at the flush: writes go into stdio's
// buffer). Reported once on the console and on LCM, then every 10000th; the
// loop never sees it and keeps the rig under control.
void TelemetryPublisher::note_log_result(int err) {
  if (err == 0) return;
  const int64_t n = log_failures_.fetch_add(1);
  if (n % 10000 != 0) return;
  const std::string text = "run log write failed: " + std::string(std::strerror(err)) + " (" +
                           std::to_string(n + 1) + " failures so far); the rig keeps running";
  spdlog::error("telemetry: {}", text);
  publish_state_event("log_write_failed", text, /*to_log=*/false);
}

void TelemetryPublisher::publish_state_event(const std::string& event, const std::string& message, bool to_log) {
  rigctl::state_t st;
  st.utime = meta_.start_utime + last_t_ns_ / 1000;
  st.tick = -1;
  st.t = static_cast<double>(last_t_ns_) * 1e-9;
  st.state = std::string(to_string(last_state_));
  st.event = event;
  st.message = message;
  st.safety_state = std::string(to_string(last_safety_state_));
  // Not into a log that is failing: that would recurse.
  emit(*lcm_, to_log ? log_.get() : nullptr, taps_, channels_.state, st.utime, st);
}

void TelemetryPublisher::report_event(const std::string& event, const std::string& message) {
  std::lock_guard<std::mutex> lock(reports_mutex_);
  reports_.emplace_back(event, message);
}

void TelemetryPublisher::publish_reports() {
  std::vector<std::pair<std::string, std::string>> reports;
  {
    std::lock_guard<std::mutex> lock(reports_mutex_);
    reports.swap(reports_);
  }
  for (const auto& [event, message] : reports) publish_state_event(event, message, log_failures_.load() == 0);
}

// A procedure's state when its counts, step or phase change, and every 40th
// tick (0.1 s at 2.5 ms) between: a console sees it move without a message
// per tick in the log.
void TelemetryPublisher::publish_procedure(const TelemetryRecord& r, int64_t utime, double t) {
  const ProcedureStatus& s = r.procedure;
  const bool changed = s.total_cycles != last_procedure_.total_cycles || s.step != last_procedure_.step ||
                       s.phase != last_procedure_.phase || s.ramp_in_cycles != last_procedure_.ramp_in_cycles ||
                       s.pass != last_procedure_.pass || s.stop_at_block_end != last_procedure_.stop_at_block_end;
  if (!changed && r.tick % 40 != 0) return;
  last_procedure_ = s;
  rigctl::procedure_t m;
  m.utime = utime;
  m.tick = r.tick;
  m.t = t;
  m.step = s.step;
  const auto step = static_cast<std::size_t>(s.step);
  m.step_name = step < meta_.procedure_step_names.size() ? meta_.procedure_step_names[step] : "";
  m.step_kind = step < meta_.procedure_step_kinds.size() ? meta_.procedure_step_kinds[step] : "";
  m.phase = std::string(to_string(s.phase));
  m.step_cycles = s.step_cycles;
  m.total_cycles = s.total_cycles;
  m.ramp_in_cycles = s.ramp_in_cycles;
  m.row = s.row;
  m.row_cycles = s.row_cycles;
  m.pass = s.pass;
  m.wanted = s.wanted;
  m.comp_gain = s.comp_gain;
  m.comp_phase = s.comp_phase;
  m.comp_mean = s.comp_mean;
  m.comp_peak = s.comp_peak;
  m.comp_valley = s.comp_valley;
  m.amplitude_error = s.amplitude_error;
  m.phase_error = s.phase_error;
  m.peak_error = s.peak_error;
  m.valley_error = s.valley_error;
  m.peak = s.peak;
  m.valley = s.valley;
  m.damage = s.damage;
  m.pv_change = s.pv_change;
  m.time_left = s.time_left_s;
  m.programmed_cycles = meta_.procedure_cycles;
  m.stop_at_block_end = s.stop_at_block_end;
  note_log_result(emit(*lcm_, log_.get(), taps_, channels_.procedure, utime, m));
}

std::optional<TelemetryRecord> TelemetryPublisher::latest() const {
  std::lock_guard<std::mutex> lock(latest_mutex_);
  return latest_;
}

void TelemetryPublisher::thread_main() {
  auto last_flush = Clock::now();
  auto last_status = last_flush;
  TelemetryRecord record;
  while (running_.load()) {
    const bool got = queue_.pop(record);
    if (got) publish_record(record);
    const auto now = Clock::now();
    if (now - last_flush >= kLogFlushInterval) {
      flush_log();
      last_flush = now;
    }
    if (now - last_status >= kDriverStatusInterval) {
      publish_driver_status();
      last_status = now;
    }
    publish_reports();
    // Polling, not a condition variable: the real-time side must never make
    // a system call to wake us.
    if (!got) std::this_thread::sleep_for(kIdleSleep);
  }
}

// The control channels after the first (a rig with several actuators).
void TelemetryPublisher::publish_more_channels(const TelemetryRecord& r, int64_t utime, double t) {
  rigctl::channels_t m;
  m.utime = utime;
  m.tick = r.tick;
  m.t = t;
  const std::size_t n = meta_.more_setpoint_names.size();
  m.num_channels = static_cast<int16_t>(n);
  m.setpoint_names = meta_.more_setpoint_names;
  for (std::size_t i = 0; i < n; ++i) {
    const ChannelTerms& c = r.more_channels[i];
    m.setpoints.push_back(c.setpoint);
    m.measurements.push_back(c.measurement);
    m.outputs.push_back(c.output);
    m.saturated.push_back(c.saturated);
  }
  note_log_result(emit(*lcm_, log_.get(), taps_, channels_.channels, utime, m));
}

void TelemetryPublisher::publish_record(const TelemetryRecord& r) {
  last_t_ns_ = r.sample.t_ns;
  const int64_t utime = meta_.start_utime + r.sample.t_ns / 1000;
  const double t = static_cast<double>(r.sample.t_ns) * 1e-9;
  lcm::LogFile* log = log_.get();
  const ChannelLayout& layout = meta_.layout;

  // The closing record of a run carries no tick of data (see has_sample).
  if (r.has_sample) {
    {
      std::lock_guard<std::mutex> lock(latest_mutex_);
      latest_ = r;
    }
    rigctl::sample_t s;
    s.utime = utime;
    s.tick = r.tick;
    s.t = t;
    s.rig = meta_.rig;
    s.status = static_cast<int32_t>(r.sample.status);
    s.num_channels = fill_channels(layout.inputs, r.sample.value, s.names, s.units, s.values);
    note_log_result(emit(*lcm_, log, taps_, channels_.sample, utime, s));

    rigctl::command_t c;
    c.utime = utime;
    c.tick = r.tick;
    c.t = t;
    c.setpoint_name = meta_.setpoint_name;
    c.setpoint = r.controller.setpoint;
    c.num_outputs = fill_channels(layout.outputs, r.command.value, c.names, c.units, c.values);
    note_log_result(emit(*lcm_, log, taps_, channels_.command, utime, c));

    rigctl::controller_t k;
    k.utime = utime;
    k.tick = r.tick;
    k.t = t;
    k.controller = meta_.controller_name;
    k.setpoint = r.controller.setpoint;
    k.measurement = r.controller.measurement;
    k.error = r.controller.error;
    const std::size_t n_terms = std::min(meta_.term_names.size(), kMaxControllerTerms);
    k.num_terms = static_cast<int16_t>(n_terms);
    k.term_names.assign(meta_.term_names.begin(), meta_.term_names.begin() + n_terms);
    k.terms.assign(r.controller.term.begin(), r.controller.term.begin() + n_terms);
    k.output_unsaturated = r.controller.output_unsaturated;
    k.output = r.controller.output;
    k.saturated = r.controller.saturated;
    k.integrator_held = r.controller.integrator_held;
    note_log_result(emit(*lcm_, log, taps_, channels_.controller, utime, k));
    if (!meta_.more_setpoint_names.empty()) publish_more_channels(r, utime, t);
    if (r.procedure.active) publish_procedure(r, utime, t);
  }

  if (first_record_ || r.state != last_state_ || r.safety_state != last_safety_state_ ||
      r.event.code != EventCode::kNone) {
    rigctl::state_t st;
    st.utime = utime;
    st.tick = r.tick;
    st.t = t;
    st.state = std::string(to_string(r.state));
    st.event = std::string(to_string(r.event.code));
    st.message = event_message(r.event, layout);
    st.safety_state = std::string(to_string(r.safety_state));
    note_log_result(emit(*lcm_, log, taps_, channels_.state, utime, st));
    first_record_ = false;
    last_state_ = r.state;
    last_safety_state_ = r.safety_state;
  }

  if (r.has_timing) {
    const TimingSummary& tm = r.timing;
    rigctl::timing_t m;
    m.utime = utime;
    m.tick = r.tick;
    m.period_ns = tm.period_ns;
    m.overrun_policy = meta_.overrun_policy;
    m.queue_policy = to_string(meta_.queue_policy);
    m.ticks = tm.ticks;
    m.overruns = tm.overruns;
    m.missed_ticks = tm.missed_ticks;
    m.dropped_records = dropped();
    m.latency_count = tm.wakeup_latency.count;
    m.latency_min_ns = tm.wakeup_latency.min_ns;
    m.latency_max_ns = tm.wakeup_latency.max_ns;
    m.latency_mean_ns = tm.wakeup_latency.mean_ns;
    m.latency_p50_ns = tm.wakeup_latency.p50_ns;
    m.latency_p99_ns = tm.wakeup_latency.p99_ns;
    m.latency_p999_ns = tm.wakeup_latency.p999_ns;
    m.compute_count = tm.compute.count;
    m.compute_min_ns = tm.compute.min_ns;
    m.compute_max_ns = tm.compute.max_ns;
    m.compute_mean_ns = tm.compute.mean_ns;
    m.compute_p50_ns = tm.compute.p50_ns;
    m.compute_p99_ns = tm.compute.p99_ns;
    m.compute_p999_ns = tm.compute.p999_ns;
    fill_stages(tm.stages, m);
    note_log_result(emit(*lcm_, log, taps_, channels_.timing, utime, m));
  }

  // Counts records (the unit dropped() counts), not LCM messages.
  published_.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace rigctl
