#include "drivers/sim/sim_canopen_valve.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/emcy.hpp"

namespace rigctl {

using namespace canopen;

namespace {

int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

constexpr int64_t kMs = 1'000'000;
constexpr uint32_t kDeviceTypeValve = 408;  // 0x1000: device profile number in the low 16 bits
constexpr uint8_t kFailSafeErrorRegister = error_register::kGeneric | error_register::kCommunication;
constexpr uint16_t kEmcyHeartbeat = 0x8130;

std::vector<OdEntry> make_dictionary(const SimCanopenValveConfig& c) {
  using A = Access;
  std::vector<OdEntry> od = {
      {0x1000, 0, 4, A::kReadOnly, kDeviceTypeValve},
      {0x1001, 0, 1, A::kReadOnly, 0},
      {0x1016, 0, 1, A::kReadOnly, 1},
      {0x1016, 1, 4, A::kReadWrite, 0},  // master heartbeat consumer: off until configured
      {0x1017, 0, 2, A::kReadWrite, c.heartbeat_period_ms},
      {0x1018, 0, 1, A::kReadOnly, 4},
      {0x1018, 1, 4, A::kReadOnly, c.vendor_id},
      {0x1018, 2, 4, A::kReadOnly, c.product_code},
      {0x1018, 3, 4, A::kReadOnly, c.revision},
      {0x1018, 4, 4, A::kReadOnly, c.serial},
      {cia408::kControlWord, 0, 2, A::kReadWrite, cia408::kControlDisabled},
      {cia408::kStatusWord, 0, 2, A::kReadOnly, 0x0009},
      {cia408::kDeviceMode, 0, 1, A::kReadWrite, 0},  // 1 = setpoint via bus must be written
      {cia408::kControlMode, 0, 1, A::kReadWrite, static_cast<uint32_t>(cia408::kControlModeSpoolClosedLoop)},
      {cia408::kSplSetpoint, 0, 1, A::kReadOnly, 1},
      {cia408::kSplSetpoint, 1, 2, A::kReadWrite, 0},
      {cia408::kSplActualValue, 0, 1, A::kReadOnly, 1},
      {cia408::kSplActualValue, 1, 2, A::kReadOnly, 0},
      {cia408::kSplReferenceValue, 0, 1, A::kReadOnly, 1},
      {cia408::kSplReferenceValue, 1, 2, A::kReadOnly, static_cast<uint32_t>(cia408::kFullScale)},
  };
  if (c.with_pressure) {
    od.push_back({cia408::kPrsActualValue, 0, 1, A::kReadOnly, 1});
    od.push_back({cia408::kPrsActualValue, 1, 2, A::kReadOnly, 0});
  }
  // PDO communication parameters, so a start-up list written for a real valve
  // (e.g. TPDO transmission type 255 with an event timer) also works here.
  // Stored; only the TPDO event timer (sub 5, ms) takes effect.
  const auto rpdo_comm = static_cast<uint16_t>(0x1400 + c.setpoint_rpdo - 1);
  const auto tpdo_comm = static_cast<uint16_t>(0x1800 + c.actual_tpdo - 1);
  od.push_back({rpdo_comm, 0, 1, A::kReadOnly, 2});
  od.push_back({rpdo_comm, 1, 4, A::kReadWrite, cob_id(rpdo(c.setpoint_rpdo), c.node_id)});
  od.push_back({rpdo_comm, 2, 1, A::kReadWrite, 255});
  od.push_back({tpdo_comm, 0, 1, A::kReadOnly, 5});
  od.push_back({tpdo_comm, 1, 4, A::kReadWrite, cob_id(tpdo(c.actual_tpdo), c.node_id)});
  od.push_back({tpdo_comm, 2, 1, A::kReadWrite, 255});
  od.push_back({tpdo_comm, 5, 2, A::kReadWrite, static_cast<uint32_t>(std::lround(c.tpdo_period_s * 1000.0))});
  return od;
}

}  // namespace

SimCanopenValve::SimCanopenValve(const std::string& socket_path, SimCanopenValveConfig config)
    : SimCanopenValve(CanTransport(), config) {
  // Delegation started no thread for a closed transport; listen, then start.
  listener_ = std::make_unique<SeqpacketListener>(socket_path);
  thread_ = std::thread([this] { run(); });
}

SimCanopenValve::SimCanopenValve(CanTransport transport, SimCanopenValveConfig config) : config_(config) {
  if (!valid_node_id(config_.node_id)) throw std::invalid_argument("simulated valve: node id must be 1..127");
  rpdo_map_ = cia408::setpoint_mapping(false);
  tpdo_map_ = cia408::actual_mapping(config_.with_pressure, cia408::kSpoolScale, config_.pressure_scale_pa);
  setpoint_cob_ = cob_id(rpdo(config_.setpoint_rpdo), config_.node_id);
  actual_cob_ = cob_id(tpdo(config_.actual_tpdo), config_.node_id);
  od_defaults_ = make_dictionary(config_);
  od_ = od_defaults_;
  sdo_ = std::make_unique<SdoServer>(config_.node_id, std::span<OdEntry>(od_));  // od_ never reallocates
  last_step_ns_ = now_ns();
  if (transport.is_open()) {
    std::lock_guard<std::mutex> lock(mutex_);
    transport_ = std::move(transport);
    connected_.store(true, std::memory_order_release);
    ++stats_.connections;
    power_on(now_ns());
    thread_ = std::thread([this] { run(); });
  }
}

SimCanopenValve::~SimCanopenValve() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

OdEntry& SimCanopenValve::od(uint16_t index, uint8_t subindex) {
  OdEntry* e = sdo_->find(index, subindex);
  return *e;  // only called for entries make_dictionary always creates
}

// ---------------------------------------------------------------- node thread

void SimCanopenValve::run() {
  while (!stop_.load(std::memory_order_acquire)) {
    if (!transport_.is_open()) {
      // No master: time goes on (the spool settles, the consumer may expire).
      std::optional<CanTransport> t;
      if (listener_) {
        t = listener_->accept(5);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      std::lock_guard<std::mutex> lock(mutex_);
      const int64_t now = now_ns();
      if (t) {
        transport_ = std::move(*t);
        connected_.store(true, std::memory_order_release);
        ++stats_.connections;
        power_on(now);  // a new connection is a power-on
      }
      step(now);
      flush(now);
      continue;
    }
    int timeout;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      timeout = wait_ms(now_ns());
    }
    CanFrame f;
    CanTransport::Rx rx = transport_.receive(f, timeout);  // only this thread touches transport_
    std::lock_guard<std::mutex> lock(mutex_);
    const int64_t now = now_ns();
    for (int n = 0; n < 64; ++n) {  // drain what is queued, then step once
      if (rx == CanTransport::Rx::kFrame) {
        handle(f, now);
      } else if (rx == CanTransport::Rx::kBadSize) {
        ++stats_.malformed;
      } else {
        break;
      }
      rx = transport_.receive(f, 0);
    }
    if (rx == CanTransport::Rx::kHangUp || rx == CanTransport::Rx::kError) drop_requested_ = true;
    step(now);
    flush(now);
    if (drop_requested_) {
      drop_requested_ = false;
      transport_.shutdown();
      transport_.close();
      out_.clear();
      connected_.store(false, std::memory_order_release);
    }
  }
}

int SimCanopenValve::wait_ms(int64_t now) const {
  int64_t due = now + 5 * kMs;
  if (!out_.empty()) due = std::min(due, out_.front().due_ns);
  if (producer_.started()) due = std::min(due, producer_.next_due_ns());
  if (nmt_state_ == NmtState::kOperational) due = std::min(due, next_tpdo_ns_);
  if (consumer_.alive() && consumer_.consumer_time_ns() > 0) {
    due = std::min(due, consumer_.last_heartbeat_ns() + consumer_.consumer_time_ns() + 1);
  }
  if (due <= now) return 0;
  return static_cast<int>(std::min<int64_t>((due - now + kMs - 1) / kMs, 5));
}

void SimCanopenValve::power_on(int64_t now) {
  setpoint_ = 0.0;
  control_word_ = cia408::kControlDisabled;
  out_.clear();
  reset_communication(now, true);
}

void SimCanopenValve::reset_communication(int64_t now, bool whole_dictionary) {
  for (std::size_t i = 0; i < od_.size(); ++i) {
    if (whole_dictionary || od_defaults_[i].index < 0x2000) od_[i].value = od_defaults_[i].value;
  }
  if (whole_dictionary) {
    setpoint_ = 0.0;
    control_word_ = cia408::kControlDisabled;
  }
  fault_.store(false, std::memory_order_release);
  after_write(0x1017, 0, now);
  after_write(0x1016, 1, now);
  tpdo_period_ns_ = static_cast<int64_t>(config_.tpdo_period_s * 1e9);
  queue(encode_heartbeat(config_.node_id, NmtState::kBootUp), now);
  set_nmt(NmtState::kPreOperational);
  next_tpdo_ns_ = now;
}

void SimCanopenValve::handle(const CanFrame& f, int64_t now) {
  CobInfo info;
  if (check_frame(f, info) != Malformed::kNone) {
    ++stats_.malformed;
    return;
  }
  switch (info.function) {
    case Function::kNmt: handle_nmt(f, now); return;
    case Function::kHeartbeat: {
      Heartbeat hb;
      if (decode_heartbeat(f, hb) != Malformed::kNone) {
        ++stats_.malformed;
        return;
      }
      consumer_.on_heartbeat(hb, now);  // ignores other nodes than the configured master
      return;
    }
    case Function::kSdoRx:
      // CiA 301: no SDO in stopped.
      if (info.node == config_.node_id && nmt_state_ != NmtState::kStopped) handle_sdo(f, now);
      return;
    default:
      if (f.id() == setpoint_cob_ && nmt_state_ == NmtState::kOperational) handle_rpdo(f);
      return;
  }
}

void SimCanopenValve::handle_nmt(const CanFrame& f, int64_t now) {
  NmtMessage m;
  if (decode_nmt(f, m) != Malformed::kNone) {
    ++stats_.malformed;
    return;
  }
  if (m.node != 0 && m.node != config_.node_id) return;
  ++stats_.nmt_commands;
  switch (m.command) {
    case NmtCommand::kStart: set_nmt(NmtState::kOperational); next_tpdo_ns_ = now; break;
    case NmtCommand::kStop: set_nmt(NmtState::kStopped); break;
    case NmtCommand::kEnterPreOperational: set_nmt(NmtState::kPreOperational); break;
    case NmtCommand::kResetNode: reset_communication(now, true); break;
    case NmtCommand::kResetCommunication: reset_communication(now, false); break;
  }
}

void SimCanopenValve::handle_rpdo(const CanFrame& f) {
  int64_t raw[2] = {0, 0};
  if (decode_pdo_raw(rpdo_map_, f, raw) != Malformed::kNone) {
    ++stats_.malformed;  // a real valve would also send EMCY 0x8210
    return;
  }
  ++stats_.rpdos;
  apply_control_word(static_cast<uint16_t>(raw[0]));
  setpoint_ = static_cast<double>(raw[1]) * cia408::kSpoolScale;
  od(cia408::kSplSetpoint, 1).value = static_cast<uint16_t>(raw[1]);
}

void SimCanopenValve::handle_sdo(const CanFrame& f, int64_t now) {
  const uint32_t writes = sdo_->writes();
  Malformed why = Malformed::kNone;
  const auto response = sdo_->on_frame(f, &why);
  if (why != Malformed::kNone) ++stats_.malformed;
  if (response) queue(*response, now);
  if (sdo_->writes() != writes) {
    ++stats_.sdo_writes;
    after_write(get_u16le(&f.data[1]), f.data[3], now);
  }
}

// Makes a written object take effect.
void SimCanopenValve::after_write(uint16_t index, uint8_t subindex, int64_t now) {
  if (index == 0x1017) {
    producer_ = HeartbeatProducer(config_.node_id, od(0x1017, 0).value * kMs);
    producer_.start(now);
  } else if (index == 0x1016 && subindex == 1) {
    const uint32_t entry = od(0x1016, 1).value;
    const auto master = static_cast<uint8_t>((entry >> 16) & 0x7F);
    consumer_ = HeartbeatConsumer(master, static_cast<int64_t>(entry & 0xFFFF) * kMs);
  } else if (index == cia408::kControlWord) {
    apply_control_word(static_cast<uint16_t>(od(index, 0).value));
  } else if (index == 0x1800 + config_.actual_tpdo - 1 && subindex == 5) {
    const uint32_t ms = od(index, 5).value;
    tpdo_period_ns_ = ms > 0 ? static_cast<int64_t>(ms) * kMs : static_cast<int64_t>(config_.tpdo_period_s * 1e9);
  } else if (index == cia408::kSplSetpoint && subindex == 1) {
    setpoint_ = sdo_sign_extend(od(index, 1).value, 2) * cia408::kSpoolScale;
  }
}

void SimCanopenValve::apply_control_word(uint16_t cw) {
  const bool fault_reset = (cw & cia408::kBitReady) != 0 && (control_word_ & cia408::kBitReady) == 0;
  if (fault_reset && fault_.load(std::memory_order_relaxed)) {
    fault_.store(false, std::memory_order_release);
    od(0x1001, 0).value = 0;
    queue(encode_emcy({config_.node_id, 0x0000, 0, {}}), last_step_ns_);
  }
  control_word_ = cw;
  od(cia408::kControlWord, 0).value = cw;
}

uint16_t SimCanopenValve::status_word() const {
  if (fault_.load(std::memory_order_relaxed)) return 0x0003;  // FAULT_HOLD: ready bit clear
  return static_cast<uint16_t>(cia408::kBitReady | (control_word_ & 0x07));
}

void SimCanopenValve::enter_fail_safe(int64_t now) {
  ++stats_.master_heartbeat_losses;
  fail_safe_ns_ = now;
  if (!fault_.exchange(true, std::memory_order_acq_rel)) {
    od(0x1001, 0).value = kFailSafeErrorRegister;
    queue(encode_emcy({config_.node_id, kEmcyHeartbeat, kFailSafeErrorRegister, {}}), now);
  }
  if (nmt_state_ == NmtState::kOperational) set_nmt(NmtState::kPreOperational);
}

void SimCanopenValve::step(int64_t now) {
  const int64_t dt = std::max<int64_t>(0, now - last_step_ns_);
  last_step_ns_ = now;
  if (consumer_.poll(now) == HeartbeatConsumer::Event::kTimedOut) enter_fail_safe(now);

  const bool drive = nmt_state_ == NmtState::kOperational && od(cia408::kDeviceMode, 0).value == 1 &&
                     (control_word_ & 0x07) == cia408::kControlActive && !fault_.load(std::memory_order_relaxed);
  const double target = drive ? std::clamp(setpoint_, -1.0, 1.0) : 0.0;
  const double tau = config_.spool_time_constant_s;
  const double alpha = tau > 0.0 ? 1.0 - std::exp(-static_cast<double>(dt) * 1e-9 / tau) : 1.0;
  spool_state_ += (target - spool_state_) * alpha;
  spool_.store(spool_state_, std::memory_order_release);
  const auto raw_actual = static_cast<int16_t>(std::lround(spool_state_ * cia408::kFullScale));
  od(cia408::kSplActualValue, 1).value = static_cast<uint16_t>(raw_actual);
  od(cia408::kStatusWord, 0).value = status_word();

  if (auto hb = producer_.poll(now, nmt_state_)) {
    if (now >= miss_heartbeats_until_ns_) queue(*hb, now);
  }
  if (nmt_state_ == NmtState::kOperational && now >= next_tpdo_ns_) {
    const double values[3] = {static_cast<double>(status_word()), spool_state_, pressure_.load(std::memory_order_acquire)};
    CanFrame f;
    encode_pdo(tpdo_map_, actual_cob_, std::span<const double>(values, tpdo_map_.size()), f);
    queue(f, now);
    const int64_t period = tpdo_period_ns_;
    next_tpdo_ns_ = now - next_tpdo_ns_ > period ? now + period : next_tpdo_ns_ + period;  // no burst after a stall
  }
}

void SimCanopenValve::queue(const CanFrame& f, int64_t now) {
  if (silent_) return;
  out_.push_back({now + delay_ns_, f, {}});
}

void SimCanopenValve::flush(int64_t now) {
  if (!transport_.is_open()) {
    out_.clear();
    return;
  }
  while (!out_.empty() && out_.front().due_ns <= now) {
    const Outgoing& o = out_.front();
    if (o.raw.empty()) {
      transport_.send(o.frame);
    } else {
      ::send(transport_.fd(), o.raw.data(), o.raw.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    }
    out_.pop_front();
  }
}

// ---------------------------------------------------------------- accessors and faults

std::optional<uint32_t> SimCanopenValve::od_value(uint16_t index, uint8_t subindex) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& e : od_) {
    if (e.index == index && e.subindex == subindex) return e.value;
  }
  return std::nullopt;
}

SimCanopenValve::Stats SimCanopenValve::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

int64_t SimCanopenValve::last_master_heartbeat_ns() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return consumer_.status() == HeartbeatConsumer::Status::kNeverSeen ? 0 : consumer_.last_heartbeat_ns();
}

int64_t SimCanopenValve::fail_safe_ns() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fail_safe_ns_;
}

void SimCanopenValve::drop_connection() {
  std::lock_guard<std::mutex> lock(mutex_);
  drop_requested_ = true;
}

void SimCanopenValve::set_silent(bool silent) {
  std::lock_guard<std::mutex> lock(mutex_);
  silent_ = silent;
}

void SimCanopenValve::set_response_delay(double s) {
  std::lock_guard<std::mutex> lock(mutex_);
  delay_ns_ = static_cast<int64_t>(std::max(0.0, s) * 1e9);
}

void SimCanopenValve::miss_heartbeats(double duration_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  miss_heartbeats_until_ns_ = now_ns() + static_cast<int64_t>(std::max(0.0, duration_s) * 1e9);
}

void SimCanopenValve::send_emcy(uint16_t code, uint8_t error_register) {
  std::lock_guard<std::mutex> lock(mutex_);
  od(0x1001, 0).value = error_register;
  queue(encode_emcy({config_.node_id, code, error_register, {}}), now_ns());
}

void SimCanopenValve::send_raw(const CanFrame& frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue(frame, now_ns());
}

void SimCanopenValve::send_raw_record(std::vector<uint8_t> bytes) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!silent_ && !bytes.empty()) out_.push_back({now_ns() + delay_ns_, CanFrame{}, std::move(bytes)});
}

void SimCanopenValve::reset_node() {
  std::lock_guard<std::mutex> lock(mutex_);
  reset_communication(now_ns(), true);
}

}  // namespace rigctl
