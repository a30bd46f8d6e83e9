#include "tools/procedure/recovery_writer.hpp"

#include <time.h>

#include <spdlog/spdlog.h>

namespace rigctl {

namespace {
// Four recoveries in flight: the writer takes the newest, the rest are
// superseded. Small, because each is tens of kilobytes.
constexpr std::size_t kQueue = 4;
constexpr timespec kIdlePoll{0, 1'000'000};  // 1 ms: well under a cycle of the fastest sine (0.1 / period)
constexpr timespec kLockstepPoll{0, 50'000};
}  // namespace

RecoveryWriter::RecoveryWriter(std::string path, RecoveryIdentity identity, bool lockstep,
                               std::function<void(const ProcedureRecovery&)> on_written)
    : path_(std::move(path)), identity_(std::move(identity)), lockstep_(lockstep), on_written_(std::move(on_written)),
      queue_(kQueue, QueueFullPolicy::kDrop), newest_(std::make_unique<ProcedureRecovery>()) {}

RecoveryWriter::~RecoveryWriter() { stop(); }

void RecoveryWriter::start() {
  running_ = true;
  queue_.set_consumer_running(true);
  thread_ = std::thread([this] { run(); });
}

void RecoveryWriter::stop() {
  if (!thread_.joinable()) return;
  running_ = false;
  thread_.join();
  queue_.set_consumer_running(false);
  drain();  // what the loop offered last
}

std::string RecoveryWriter::error() const { return failed_.load() ? error_ : std::string(); }

void RecoveryWriter::offer(const ProcedureRecovery& r) noexcept {
  // A full queue drops the oldest's successor; in lockstep the queue is
  // empty here (each offer waits for its own write).
  queue_.push(r);
  if (!lockstep_) return;
  while (running_.load(std::memory_order_acquire) && !failed_.load(std::memory_order_relaxed) &&
         written_sequence_.load(std::memory_order_acquire) < r.sequence) {
    nanosleep(&kLockstepPoll, nullptr);
  }
}

bool RecoveryWriter::drain() {
  bool any = false;
  while (queue_.pop(*newest_)) any = true;
  if (!any || failed_.load()) return any;
  try {
    write_recovery_file(path_, identity_, *newest_);
    ++written_count_;
    if (on_written_) on_written_(*newest_);
  } catch (const std::exception& e) {
    error_ = e.what();
    failed_ = true;
    spdlog::error("{}: the test goes on without a recovery file", e.what());
  }
  written_sequence_.store(newest_->sequence, std::memory_order_release);
  return true;
}

void RecoveryWriter::run() {
  while (running_.load(std::memory_order_acquire)) {
    if (!drain()) nanosleep(&kIdlePoll, nullptr);
  }
}

}  // namespace rigctl
