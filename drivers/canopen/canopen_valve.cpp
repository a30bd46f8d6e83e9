// CanopenValve: construction, start/stop, the real-time API and diagnostics.
// The start-up sequence is in canopen_valve_startup.cpp, frame handling in
// canopen_valve_io.cpp.
#include "drivers/canopen/canopen_valve.hpp"

#include "rt/realtime.hpp"

#include <cstring>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl {

using namespace canopen;

namespace {

int64_t to_ns(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

const CanopenValveConfig& validated(const CanopenValveConfig& c) {
  auto bad = [](const std::string& why) { throw std::invalid_argument("canopen valve config: " + why); };
  // Neither is allowed for a valve always started on a caller-made transport
  // (tests); start() without one then fails. The config reader requires one.
  if (!c.interface.empty() && !c.socket_path.empty()) bad("give only one of interface and socket_path");
  if (!valid_node_id(c.node_id) || !valid_node_id(c.master_node_id)) bad("node ids must be 1..127");
  if (c.node_id == c.master_node_id) bad("node_id and master_node_id must differ");
  if (!(c.heartbeat_timeout_s > 0.0) || !(c.heartbeat_period_s > 0.0)) bad("heartbeat times must be > 0");
  if (c.configure_heartbeats) {
    if (!(c.valve_heartbeat_period_s >= 0.001 && c.valve_heartbeat_period_s <= 65.535)) bad("valve_heartbeat_period_s must be 0.001..65.535");
    if (!(c.valve_consumer_time_s >= 0.001 && c.valve_consumer_time_s <= 65.535)) bad("valve_consumer_time_s must be 0.001..65.535");
    if (c.valve_heartbeat_period_s >= c.heartbeat_timeout_s) bad("valve_heartbeat_period_s must be < heartbeat_timeout_s");
    if (c.valve_consumer_time_s <= c.heartbeat_period_s) bad("valve_consumer_time_s must be > heartbeat_period_s");
  }
  if (!(c.sdo_timeout_s > 0.0) || !(c.startup_timeout_s > 0.0)) bad("sdo and start-up timeouts must be > 0");
  if (!(c.boot_timeout_s > 0.0) || !(c.device_state_timeout_s > 0.0)) bad("boot and device state timeouts must be > 0");
  if (!(c.actual_max_age_s > 0.0)) bad("actual_max_age_s must be > 0");
  if (!(c.actual_period_s >= 0.001 && c.actual_period_s <= 65.535)) bad("actual_period_s must be 0.001..65.535");
  if (!(c.actual_period_s < c.actual_max_age_s)) bad("actual_period_s must be < actual_max_age_s");
  // The I/O thread repeats the null setpoint every quarter of it, at least every millisecond.
  if (!(c.setpoint_timeout_s == 0.0 || (c.setpoint_timeout_s >= 0.004 && c.setpoint_timeout_s <= 65.535))) {
    bad("setpoint_timeout_s must be 0 (off) or 0.004..65.535");
  }
  if (c.spool_full_scale < 0 || c.spool_full_scale > 32767) bad("spool_full_scale must be 0 (the valve's) or 1..32767");
  if (c.setpoint_rpdo < 1 || c.setpoint_rpdo > 4 || c.actual_tpdo < 1 || c.actual_tpdo > 4) bad("PDO numbers must be 1..4");
  if (c.actual_input.empty()) bad("actual_input must name an input channel");
  if (!c.pressure_input.empty() && (!std::isfinite(c.pressure_scale_pa) || c.pressure_scale_pa == 0.0)) {
    bad("pressure_scale_pa must be finite and non-zero");
  }
  for (const auto& w : c.startup_sdo) {
    if (w.size < 1 || w.size > 4) bad("start-up SDO write '" + w.name + "': size must be 1..4 bytes");
  }
  return c;
}

}  // namespace

CanopenValve::CanopenValve(CanopenValveConfig config)
    : config_(validated(config)),
      consumer_(config_.node_id, to_ns(config_.heartbeat_timeout_s)),
      producer_(config_.master_node_id, to_ns(config_.heartbeat_period_s)),
      sdo_(config_.node_id, to_ns(config_.sdo_timeout_s)) {
  set_spool_scale(config_.spool_full_scale > 0 ? config_.spool_full_scale : cia408::kFullScale);
  setpoint_cob_ = cob_id(rpdo(config_.setpoint_rpdo), config_.node_id);
  actual_cob_ = cob_id(tpdo(config_.actual_tpdo), config_.node_id);
  max_age_ns_ = to_ns(config_.actual_max_age_s);
  heartbeat_timeout_ns_ = to_ns(config_.heartbeat_timeout_s);
  // A quarter of the valve's setpoint deadline leaves three repeats to be
  // lost or late; with no deadline in the valve, our heartbeat's period.
  keepalive_ns_ = config_.setpoint_timeout_s > 0.0 ? to_ns(config_.setpoint_timeout_s / 4.0)
                                                   : to_ns(config_.heartbeat_period_s);
}

void CanopenValve::set_spool_scale(int full_scale) {
  spool_full_scale_ = full_scale;
  const double scale = 1.0 / full_scale;
  rpdo_map_ = cia408::setpoint_mapping(false, scale);
  tpdo_map_ = cia408::actual_mapping(!config_.pressure_input.empty(), scale, config_.pressure_scale_pa);
}

CanopenValve::~CanopenValve() { stop(); }

int64_t CanopenValve::clock_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::string CanopenValve::prefix() const { return "canopen valve node " + std::to_string(config_.node_id) + ": "; }

void CanopenValve::start() {
  const int64_t deadline = clock_ns() + to_ns(config_.startup_timeout_s);
  start_session(open_transport(deadline), deadline);
}

void CanopenValve::start(CanTransport transport) {
  start_session(std::move(transport), clock_ns() + to_ns(config_.startup_timeout_s));
}

void CanopenValve::start_session(CanTransport transport, int64_t deadline_ns) {
  if (running() || io_thread_.joinable()) throw std::logic_error(prefix() + "start() while running");
  {
    std::lock_guard<std::mutex> lock(admin_mutex_);
    retire_transport();
    transport_ = std::move(transport);
  }
  // A fresh session: nothing latched from the previous one.
  consumer_.reset();
  producer_ = HeartbeatProducer(config_.master_node_id, to_ns(config_.heartbeat_period_s));
  sdo_.cancel();
  sdo_result_.reset();
  link_lost_ = false;
  expect_operational_ = false;
  actual_count_ = 0;
  malformed_reported_ = {};
  bad_size_reported_ = false;
  last_status_word_ = 0;
  latest_.store(ValveActual{});
  last_heartbeat_ns_.store(0, std::memory_order_release);
  valve_state_.store(static_cast<uint8_t>(NmtState::kBootUp), std::memory_order_release);
  faults_.store(kFaultNotRunning, std::memory_order_release);
  first_flag_.store(static_cast<uint8_t>(FlagReason::kNone), std::memory_order_release);
  safe_hold_.store(true, std::memory_order_release);

  try {
    // We produce a heartbeat the valve watches from 0x1016:1 on: at the I/O
    // thread's priority, not as a normal thread a busy machine can starve
    // past the valve's consumer time in the middle of start-up.
    ScopedFifoPriority priority(config_.io_priority);
    if (priority.error() != 0) {
      events_.push(prefix() + "cannot give the start-up thread SCHED_FIFO priority " +
                   std::to_string(config_.io_priority) + " (" + std::strerror(priority.error()) + "); it runs best effort");
    }
    run_startup(deadline_ns);
  } catch (...) {
    send(encode_nmt(NmtCommand::kEnterPreOperational, config_.node_id));  // best effort: no PDOs to a half-started valve
    std::lock_guard<std::mutex> lock(admin_mutex_);
    retire_transport();
    throw;
  }
  // What happened during start-up (our own reset, heartbeats not yet
  // configured, the device state walk) is not a fault of the session; an
  // active EMCY is.
  expect_operational_ = true;
  consumer_.clear_reset();
  clear_fault(kFaultNotRunning | kFaultHeartbeatLost | kFaultValveReset | kFaultNotOperational | kFaultLinkLost |
              kFaultDeviceState);
  next_keepalive_ns_ = clock_ns() + keepalive_ns_;
  stop_requested_.store(false, std::memory_order_release);
  io_thread_ = std::thread([this] { io_loop(); });
  // Heartbeats and actual values are stamped by this thread: starved, it
  // would make a healthy valve look stale.
  if (config_.io_priority > 0) {
    if (const int rc = set_fifo_priority(io_thread_, config_.io_priority); rc != 0) {
      events_.push(prefix() + "cannot give the I/O thread SCHED_FIFO priority " +
                   std::to_string(config_.io_priority) + " (" + std::strerror(rc) + "); it runs best effort");
    }
  }
  running_.store(true, std::memory_order_release);
  events_.push(prefix() + "started: configured, NMT operational, DEVICE MODE ACTIVE at null");
}

void CanopenValve::retire_transport() {
  if (!transport_.is_open()) return;
  const auto c = transport_.counters();
  transport_totals_.tx += c.tx;
  transport_totals_.tx_dropped += c.tx_dropped;
  transport_totals_.tx_errors += c.tx_errors;
  transport_totals_.rx += c.rx;
  transport_totals_.rx_bad_size += c.rx_bad_size;
  transport_ = CanTransport();
}

void CanopenValve::stop() noexcept {
  const bool was_running = running_.exchange(false, std::memory_order_acq_rel);
  if (was_running) {
    send_rpdo(cia408::kControlActive, 0.0);
    send(encode_nmt(NmtCommand::kEnterPreOperational, config_.node_id));
  }
  stop_requested_.store(true, std::memory_order_release);
  try {
    if (io_thread_.joinable()) io_thread_.join();
    set_fault(kFaultNotRunning);
    std::lock_guard<std::mutex> lock(admin_mutex_);
    retire_transport();
    if (was_running) events_.push(prefix() + "stopped: null setpoint sent, NMT enter pre-operational");
  } catch (...) {
    // join() or an allocation failed: nothing sensible is left to do on a way out.
  }
}

// ---------------------------------------------------------------- real time

void CanopenValve::send_rpdo(uint16_t control_word, double fraction) noexcept {
  const double v = std::isnan(fraction) ? 0.0 : std::clamp(fraction, -1.0, 1.0);
  const double values[2] = {static_cast<double>(control_word), v};
  CanFrame f;
  encode_pdo(rpdo_map_, setpoint_cob_, std::span<const double>(values, 2), f);
  transport_.send(f);  // a full buffer drops the frame and counts it; next tick sends again
}

void CanopenValve::write_setpoint(double fraction) noexcept {
  if (!running_.load(std::memory_order_acquire)) return;
  safe_hold_.store(false, std::memory_order_release);
  send_rpdo(cia408::kControlActive, fraction);
}

void CanopenValve::make_safe() noexcept {
  if (!running_.load(std::memory_order_acquire)) return;
  // Set before the send: a keep-alive the I/O thread sends in between is
  // the same null setpoint.
  safe_hold_.store(true, std::memory_order_release);
  send_rpdo(cia408::kControlActive, 0.0);
}

ValveIdentity CanopenValve::identity() const {
  std::lock_guard<std::mutex> lock(admin_mutex_);
  return identity_;
}

ValveActual CanopenValve::latest_actual() const noexcept {
  ValveActual a;
  if (!latest_.load(a)) a = ValveActual{};
  return a;
}

namespace {
// |now - then| within limit; a value far in the future means the caller's
// clock is not CLOCK_MONOTONIC, which must not pass as fresh.
bool fresh(int64_t then_ns, int64_t now_ns, int64_t limit_ns) {
  const int64_t age = now_ns - then_ns;
  return age <= limit_ns && age >= -limit_ns;
}
}  // namespace

// Why the inputs must not be used now (kNone: they may). The latched faults
// first, most telling first; then the checks on the loop's own clock.
CanopenValve::FlagReason CanopenValve::flag_reason(const ValveActual& a, bool have, int64_t now_ns) const noexcept {
  const uint32_t f = faults_.load(std::memory_order_acquire);
  if (f & kFaultLinkLost) return FlagReason::kLinkLost;
  if (f & kFaultValveReset) return FlagReason::kValveReset;
  if (f & kFaultHeartbeatLost) return FlagReason::kHeartbeatLost;
  if (f & kFaultEmcy) return FlagReason::kEmcy;
  if (f & kFaultNotOperational) return FlagReason::kNotOperational;
  if (f & kFaultDeviceState) return FlagReason::kDeviceState;
  // Checked here on the loop's clock as well as by the I/O thread, so a
  // stalled I/O thread cannot hide a silent valve.
  const int64_t hb = last_heartbeat_ns_.load(std::memory_order_acquire);
  if (hb == 0 || !fresh(hb, now_ns, heartbeat_timeout_ns_)) return FlagReason::kHeartbeatStale;
  if (!have) return FlagReason::kNoActualValue;
  if (!fresh(a.rx_ns, now_ns, max_age_ns_)) return FlagReason::kActualStale;
  // Only DEVICE MODE ACTIVE follows the bus setpoint: the ready bit alone is
  // also set in INIT, DISABLED and HOLD.
  if (cia408::valve_state(a.status_word) != cia408::ValveState::kActive) return FlagReason::kDeviceState;
  return FlagReason::kNone;
}

void CanopenValve::note_flag(FlagReason why, const ValveActual& a, int64_t now_ns) const noexcept {
  uint8_t none = static_cast<uint8_t>(FlagReason::kNone);
  if (first_flag_.load(std::memory_order_relaxed) != none) return;
  const bool latched_state = (faults_.load(std::memory_order_relaxed) & kFaultDeviceState) != 0;
  first_flag_status_word_.store(latched_state ? left_active_status_word_.load(std::memory_order_relaxed) : a.status_word,
                                std::memory_order_relaxed);
  const int64_t since = why == FlagReason::kHeartbeatStale ? last_heartbeat_ns_.load(std::memory_order_relaxed) : a.rx_ns;
  first_flag_age_ns_.store(since == 0 ? -1 : now_ns - since, std::memory_order_relaxed);
  first_flag_nmt_.store(valve_state_.load(std::memory_order_relaxed), std::memory_order_relaxed);
  first_flag_.compare_exchange_strong(none, static_cast<uint8_t>(why), std::memory_order_acq_rel);
}

bool CanopenValve::healthy(int64_t now_ns) const noexcept {
  if (!running_.load(std::memory_order_acquire)) return false;
  ValveActual a;
  const bool have = latest_.load(a) && a.count > 0;
  return flag_reason(a, have, now_ns) == FlagReason::kNone;
}

void CanopenValve::read_actual(Sample& out, std::size_t first_index, int64_t now_ns) const noexcept {
  const std::size_t n = input_count();
  if (first_index + n > kMaxInputs) return;
  const ValveActual a = load_or_keep(latest_, loop_copy_);  // one consistent copy for values and checks
  const bool have = a.count > 0;
  out.value[first_index] = have ? a.spool : 0.0;
  if (n == 2) out.value[first_index + 1] = have ? a.pressure : 0.0;
  bool usable = false;
  if (running_.load(std::memory_order_acquire)) {
    const FlagReason why = flag_reason(a, have, now_ns);
    usable = why == FlagReason::kNone;
    if (!usable) note_flag(why, a, now_ns);
  }
  if (!usable) {
    const uint32_t mask = n == 2 ? 3U : 1U;
    out.status |= mask << first_index;
  }
}

// ---------------------------------------------------------------- diagnostics

std::vector<ChannelInfo> CanopenValve::input_channels() const {
  std::vector<ChannelInfo> ch{{config_.actual_input, "1"}};
  if (!config_.pressure_input.empty()) ch.push_back({config_.pressure_input, "Pa"});
  return ch;
}

DriverDiagnostics CanopenValve::diagnostics() {
  DriverDiagnostics d;
  CanTransport::Counters t;
  {
    std::lock_guard<std::mutex> lock(admin_mutex_);
    t = transport_totals_;
    const auto c = transport_.counters();
    t.tx += c.tx;
    t.tx_dropped += c.tx_dropped;
    t.tx_errors += c.tx_errors;
    t.rx += c.rx;
    t.rx_bad_size += c.rx_bad_size;
  }
  auto add = [&d](const char* name, uint64_t v) { d.counters.emplace_back(name, static_cast<int64_t>(v)); };
  auto get = [](const std::atomic<uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  add("canopen_rx_frames", t.rx);
  add("canopen_tx_frames", t.tx);
  add("canopen_tx_dropped", t.tx_dropped);
  add("canopen_tx_errors", t.tx_errors);
  add("canopen_frames_accepted", get(counters_.accepted));
  add("canopen_frames_ignored", get(counters_.ignored));
  uint64_t malformed = t.rx_bad_size;
  for (std::size_t i = 1; i < kMalformedReasons; ++i) malformed += get(counters_.malformed[i]);
  add("canopen_malformed_frames", malformed);
  add("canopen_malformed_bad_record_size", t.rx_bad_size);
  add("canopen_malformed_not_data_frame", get(counters_.malformed[static_cast<std::size_t>(Malformed::kNotDataFrame)]));
  add("canopen_malformed_unknown_cob_id", get(counters_.malformed[static_cast<std::size_t>(Malformed::kUnknownCobId)]));
  add("canopen_malformed_wrong_length", get(counters_.malformed[static_cast<std::size_t>(Malformed::kWrongLength)]));
  add("canopen_malformed_bad_content", get(counters_.malformed[static_cast<std::size_t>(Malformed::kBadContent)]));
  add("canopen_malformed_unexpected_sdo", get(counters_.malformed[static_cast<std::size_t>(Malformed::kUnexpectedSdo)]));
  add("canopen_malformed_bad_pdo_length", get(counters_.malformed[static_cast<std::size_t>(Malformed::kBadPdoLength)]));
  add("canopen_actual_received", get(counters_.actual));
  add("canopen_heartbeat_timeouts", get(counters_.heartbeat_timeouts));
  add("canopen_valve_resets", get(counters_.valve_resets));
  add("canopen_emcy", get(counters_.emcy));
  add("canopen_sdo_aborts", get(counters_.sdo_aborts));
  add("canopen_sdo_retries", get(counters_.sdo_retries));
  add("canopen_discarded_before_reset", get(counters_.discarded_before_reset));
  add("canopen_left_device_mode_active", get(counters_.left_active));
  add("canopen_null_setpoint_repeats", get(counters_.keepalives));
  add("canopen_link_lost", get(counters_.link_lost));
  add("canopen_events_dropped", events_.dropped());
  d.events = events_.drain();
  return d;
}

}  // namespace rigctl
