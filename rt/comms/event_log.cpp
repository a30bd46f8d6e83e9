#include "rt/comms/event_log.hpp"
#include "rt/wall_clock.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>

#include "rt/comms/event_text.hpp"

namespace rigctl {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPoll = std::chrono::milliseconds(1);
constexpr auto kRetry = std::chrono::seconds(1);

// ISO 8601 UTC with microseconds, from microseconds since the epoch.
std::string iso_utc(int64_t utime) {
  const std::time_t s = static_cast<std::time_t>(utime / 1'000'000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[64];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  std::snprintf(buf + n, sizeof buf - n, ".%06lldZ", static_cast<long long>(utime % 1'000'000));
  return buf;
}

}  // namespace

EventLog::EventLog(std::string path, EventLogMeta meta)
    : path_(std::move(path)), meta_(std::move(meta)), queue_(kQueueCapacity, meta_.queue_policy) {
  const std::filesystem::path parent = std::filesystem::path(path_).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error("event log: cannot open '" + path_ + "' for appending: " + std::strerror(errno));
}

EventLog::~EventLog() { stop(); }

bool EventLog::push(const EventRecord& record) noexcept { return queue_.push(record); }

void EventLog::push_note(int64_t wall_utime, const std::string& code, const std::string& source, int64_t sequence,
                         const std::string& message) {
  char head[64];
  std::snprintf(head, sizeof head, " t=%.6f tick=- state=-", static_cast<double>(wall_utime - meta_.start_utime) * 1e-6);
  std::string line = iso_utc(wall_utime) + head + " code=" + code + " source=" + source;
  if (sequence != 0) line += " seq=" + std::to_string(sequence);
  // The text may carry bytes from the network (a rejected command's fields):
  // no newline, quote or control character may forge or break a line.
  line += " message=\"";
  for (const char ch : message) line += (static_cast<unsigned char>(ch) < 0x20 || ch == '"' || ch == 0x7f) ? '?' : ch;
  line += "\"";
  const std::lock_guard<std::mutex> lock(notes_mutex_);
  if (notes_.size() < kMaxPendingLines) notes_.push_back(std::move(line));
}

std::string EventLog::format(const EventRecord& r) const {
  char head[160];
  std::snprintf(head, sizeof head, " t=%.6f tick=%lld", static_cast<double>(r.t_ns) * 1e-9,
                static_cast<long long>(r.tick));
  std::string line = iso_utc(meta_.start_utime + r.t_ns / 1000) + head;
  line += " state=" + std::string(to_string(r.state));
  line += " code=" + std::string(to_string(r.event.code));
  const std::string channel = r.event.code == EventCode::kCommandRejected ? "" : input_name(r.event.channel, meta_.layout);
  if (!channel.empty()) line += " channel=" + channel;
  char value[48];
  std::snprintf(value, sizeof value, " value=%.9g", r.event.value);
  line += value;
  line += " source=" + std::string(to_string(r.source));
  if (r.source == EventSource::kOperator) line += " seq=" + std::to_string(r.sequence);
  if (r.event.code == EventCode::kStateChanged && r.cause != EventCode::kNone) {
    line += " cause=" + std::string(to_string(r.cause));
  }
  line += " message=\"" + event_message(r.event, meta_.layout) + "\"";
  return line;
}

bool EventLog::write_line(const std::string& text) {
  const std::string line = text + "\n";
  const auto t0 = Clock::now();
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd_, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      // A partial line would corrupt the file: cut it back (O_APPEND wrote at the end).
      if (done > 0) {
        const off_t end = ::lseek(fd_, 0, SEEK_END);
        if (end >= static_cast<off_t>(done) && ::ftruncate(fd_, end - static_cast<off_t>(done)) != 0) {
          // nothing more to do: the reader skips a line without a newline
        }
      }
      errno = err;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  // fsync on a device that cannot sync (a pipe, /dev/null) is not a failure of the record.
  if (::fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) return false;
  const int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
  int64_t prev = max_fsync_ns_.load();
  while (ns > prev && !max_fsync_ns_.compare_exchange_weak(prev, ns)) {
  }
  written_.fetch_add(1);
  return true;
}

void EventLog::flush_pending() {
  while (!pending_.empty()) {
    if (!write_line(pending_.front())) {
      const int err = errno;
      const int64_t n = failures_.fetch_add(1);
      if (n % 1000 == 0 && on_failure_) {
        on_failure_("event log '" + path_ + "': write failed: " + std::strerror(err) + " (" +
                    std::to_string(pending_.size()) + " events kept in memory, retried every second)");
      }
      break;
    }
    pending_.pop_front();
  }
  pending_count_.store(static_cast<int64_t>(pending_.size()));
}

void EventLog::drain() {
  EventRecord r;
  bool any = false;
  while (queue_.pop(r)) {
    if (pending_.size() < kMaxPendingLines) pending_.push_back(format(r));
    any = true;
  }
  {
    const std::lock_guard<std::mutex> lock(notes_mutex_);
    for (; !notes_.empty(); notes_.pop_front()) {
      if (pending_.size() < kMaxPendingLines) pending_.push_back(std::move(notes_.front()));
      any = true;
    }
  }
  if (any) flush_pending();
}

void EventLog::start() {
  if (thread_.joinable()) return;
  pending_.push_back("# rigctl event log: rig " + meta_.rig + ", opened " + iso_utc(wall_utime_now()) +
                     "; one line per event: wall time (UTC), rig time t [s], tick, state after the event, code, "
                     "channel, value, source, message; a full queue: " +
                     (meta_.queue_policy == QueueFullPolicy::kWait ? std::string("the loop waits (simulated time)")
                                                                     : std::string("dropped and counted (paced run)")));
  flush_pending();
  running_.store(true);
  queue_.set_consumer_running(true);
  thread_ = std::thread([this] { thread_main(); });
}

void EventLog::thread_main() {
  auto last_retry = Clock::now();
  while (running_.load()) {
    drain();
    if (!pending_.empty() && Clock::now() - last_retry >= kRetry) {
      flush_pending();
      last_retry = Clock::now();
    }
    // Polling, not a condition variable: the loop must never make a system call to wake us.
    std::this_thread::sleep_for(kPoll);
  }
}

void EventLog::stop() {
  if (stopped_) return;
  stopped_ = true;
  queue_.set_consumer_running(false);
  running_.store(false);
  if (thread_.joinable()) thread_.join();
  drain();
  pending_.push_back("# closed cleanly " + iso_utc(wall_utime_now()) + ": " + std::to_string(written_.load()) +
                     " lines written, " + std::to_string(queue_.dropped()) + " dropped");
  flush_pending();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

EventLogStats EventLog::stats() const {
  EventLogStats s;
  s.written = written_.load();
  s.pending = pending_count_.load();
  s.write_failures = failures_.load();
  s.dropped = queue_.dropped();
  s.max_fsync_ms = static_cast<double>(max_fsync_ns_.load()) * 1e-6;
  return s;
}

}  // namespace rigctl
