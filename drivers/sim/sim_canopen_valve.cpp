// SimCanopenValve: construction, the node's thread and connections, the
// accessors and the fault injectors. Frame handling and the node's
// behaviour are in sim_canopen_valve_node.cpp.
#include "drivers/sim/sim_canopen_valve.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <stdexcept>

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

}  // namespace

SimCanopenValve::SimCanopenValve(const std::string& socket_path, SimCanopenValveConfig config)
    : SimCanopenValve(CanTransport(), config) {
  // Delegation started no thread for a closed transport; listen, then start.
  listener_ = std::make_unique<SeqpacketListener>(socket_path);
  thread_ = std::thread([this] { run(); });
}

SimCanopenValve::SimCanopenValve(CanTransport transport, SimCanopenValveConfig config) : config_(config) {
  if (!valid_node_id(config_.node_id)) throw std::invalid_argument("simulated valve: node id must be 1..127");
  if (config_.spool_reference <= 0) throw std::invalid_argument("simulated valve: spool_reference must be > 0");
  od_defaults_ = make_valve_dictionary(config_);
  od_ = od_defaults_;
  sdo_ = std::make_unique<SdoServer>(config_.node_id, std::span<OdEntry>(od_));  // od_ never reallocates
  sdo_->set_write_check([this](const OdEntry& e, uint32_t value) { return pdo_write_refusal(od_, e, value); });
  sdo_->set_segmented_uploads(config_.segmented_uploads);
  dsm_.set_stall(config_.stall_at);
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
  { std::lock_guard<std::mutex> lock(mutex_); }
  pass_done_.notify_all();  // a take_pending_frames() waiting now returns
}

OdEntry& SimCanopenValve::od(uint16_t index, uint8_t subindex) {
  OdEntry* e = sdo_->find(index, subindex);
  return *e;  // only called for entries make_valve_dictionary always creates
}

// ---------------------------------------------------------------- node thread

void SimCanopenValve::run() {
  while (!stop_.load(std::memory_order_acquire)) {
    if (transport_.is_open()) {
      serve_frames();
      continue;
    }
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
    ++passes_;
    pass_done_.notify_all();
  }
}

void SimCanopenValve::take_pending_frames() {
  std::unique_lock<std::mutex> lock(mutex_);
  // A pass already under way may have looked at the socket before the
  // frames came; the one after it starts later and takes them.
  const uint64_t wanted = passes_ + 2;
  pass_done_.wait(lock, [&] { return passes_ >= wanted || stop_.load(std::memory_order_acquire); });
}

// Waits for frames until something is due, handles what is queued, steps once.
void SimCanopenValve::serve_frames() {
  int timeout;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    timeout = wait_ms(now_ns());
  }
  CanFrame f;
  CanTransport::Rx rx = transport_.receive(f, timeout);  // only this thread touches transport_
  std::lock_guard<std::mutex> lock(mutex_);
  const int64_t now = now_ns();
  for (int n = 0; n < 64; ++n) {
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
  ++passes_;
  pass_done_.notify_all();
  if (drop_requested_) {
    drop_requested_ = false;
    transport_.shutdown();
    transport_.close();
    out_.clear();
    connected_.store(false, std::memory_order_release);
  }
}

int SimCanopenValve::wait_ms(int64_t now) const {
  int64_t due = now + 5 * kMs;
  if (!out_.empty()) due = std::min(due, out_.front().due_ns);
  if (boot_until_ns_ != 0) due = std::min(due, boot_until_ns_);
  if (producer_.started()) due = std::min(due, producer_.next_due_ns());
  if (nmt_state_ == NmtState::kOperational) due = std::min(due, next_tpdo_ns_);
  if (rpdo_deadline_ns_ != 0) due = std::min(due, rpdo_deadline_ns_ + 1);
  if (consumer_.alive() && consumer_.consumer_time_ns() > 0) {
    due = std::min(due, consumer_.last_heartbeat_ns() + consumer_.consumer_time_ns() + 1);
  }
  if (due <= now) return 0;
  return static_cast<int>(std::min<int64_t>((due - now + kMs - 1) / kMs, 5));
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
  return od_get(od_, index, subindex);
}

cia408::ValveState SimCanopenValve::device_state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dsm_.state();
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

void SimCanopenValve::fault_device(uint16_t emcy_code) {
  std::lock_guard<std::mutex> lock(mutex_);
  enter_fail_safe(now_ns(), emcy_code);
}

void SimCanopenValve::lose_sdo_answers(int count) {
  std::lock_guard<std::mutex> lock(mutex_);
  sdo_answers_to_lose_ = std::max(0, count);
}

void SimCanopenValve::drop_to_hold(double duration_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  dsm_.force_hold(now_ns() + static_cast<int64_t>(std::max(0.0, duration_s) * 1e9));
}

}  // namespace rigctl
