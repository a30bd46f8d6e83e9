// The durable event log: one line per event (state change, limit trip,
// operator command, run start and end), appended to its own file and
// fsync'd line by line by a writer thread. Events are rare, so each one is on
// the disk within a poll period (1 ms) plus one fsync of the moment it
// happened; a kill -9 of the controller loses none that were written.
//
// The loop pushes fixed-size EventRecords into a lock-free queue; a paced
// loop never waits, one in simulated time waits when the queue is full
// (EventLogMeta::queue_policy, rt/queue_full_policy.hpp). A failing disk (full, I/O error) is reported through on_failure
// (console and LCM); the lines are kept in memory (up to kMaxPendingLines)
// and retried once a second, so a disk that frees up still gets them all.
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "rt/bounded_handoff.hpp"
#include "rt/comms/event_sink.hpp"
#include "rt/queue_full_policy.hpp"
#include "rt/sample.hpp"

namespace rigctl {

struct EventLogMeta {
  std::string rig;
  ChannelLayout layout;      // channel names for the messages
  int64_t start_utime = 0;   // wall-clock time of rig time 0 [us since the epoch], as the LCM log
  QueueFullPolicy queue_policy = QueueFullPolicy::kDrop;  // as the telemetry's: the loop's clock decides
};

struct EventLogStats {
  int64_t written = 0;       // lines on the disk (fsync'd)
  int64_t pending = 0;       // lines waiting for a disk that failed
  int64_t write_failures = 0;
  int64_t dropped = 0;       // refused by a full queue (kDrop only; never seen in practice: 4096 slots)
  double max_fsync_ms = 0.0;  // longest write + fsync of one line
};

class EventLog final : public EventSink {
 public:
  static constexpr std::size_t kQueueCapacity = 4096;
  static constexpr std::size_t kMaxPendingLines = 100000;

  // Opens (creates, appends to) `path`. Throws std::runtime_error naming the
  // path when it cannot be opened.
  EventLog(std::string path, EventLogMeta meta);
  ~EventLog() override;
  EventLog(const EventLog&) = delete;
  EventLog& operator=(const EventLog&) = delete;

  // Loop thread: kDrop never blocks; kWait waits for the writer when full.
  bool push(const EventRecord& record) noexcept override;

  // Other (non-real-time) threads: an event the loop never saw, e.g. an
  // operator command the receiver rejected (bad tag, stale, replayed). Takes
  // a mutex; written by the writer thread in arrival order with the loop's
  // events. The line has wall time and t but no tick or state (tick=- state=-).
  void push_note(int64_t wall_utime, const std::string& code, const std::string& source, int64_t sequence,
                 const std::string& message);

  // Called on the writer thread on the first failure and every 1000th after,
  // with a message naming the file and the error. Set before start().
  void set_failure_handler(std::function<void(const std::string&)> handler) { on_failure_ = std::move(handler); }

  void start();
  // Drains the queue, writes the closing line, fsyncs and closes.
  void stop();

  EventLogStats stats() const;
  const std::string& path() const { return path_; }

  // The text of one record as written (without the newline).
  std::string format(const EventRecord& r) const;

 private:
  void thread_main();
  void drain();
  bool write_line(const std::string& line);  // write + fsync; false on failure
  void flush_pending();

  std::string path_;
  EventLogMeta meta_;
  int fd_ = -1;
  BoundedHandoff<EventRecord> queue_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  bool stopped_ = false;
  std::deque<std::string> pending_;  // writer thread only
  std::mutex notes_mutex_;
  std::deque<std::string> notes_;    // push_note() lines, guarded by notes_mutex_
  std::function<void(const std::string&)> on_failure_;
  std::atomic<int64_t> written_{0}, failures_{0}, pending_count_{0};
  std::atomic<int64_t> max_fsync_ns_{0};
};

}  // namespace rigctl
