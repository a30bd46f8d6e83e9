// systemd readiness and watchdog for `rigctl run` as a service
// (systemd/rigctl.service, Type=notify, WatchdogSec=). Outside systemd
// (no NOTIFY_SOCKET) it does nothing.
//
// Its own thread, started before the loop takes SCHED_FIFO so it keeps normal
// priority, watches a counter the loop advances every tick
// (tools/run/loop_heartbeat.hpp):
//   * READY=1 once the loop has ticked: the rig is controlled, not merely
//     the process started;
//   * WATCHDOG=1 every half watchdog interval, but only if the counter moved
//     since the last check. A stuck loop (blocked driver, livelock) stops the
//     pings even though this thread still runs, and systemd kills the
//     process after WatchdogSec.
// The notify protocol itself is libsystemd's sd_notify (not re-implemented).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace rigctl {

class ServiceNotifier {
 public:
  // Reads NOTIFY_SOCKET and WATCHDOG_USEC/WATCHDOG_PID (sd_watchdog_enabled).
  explicit ServiceNotifier(const std::atomic<int64_t>& beats);
  ~ServiceNotifier();
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;

  bool active() const { return active_; }          // NOTIFY_SOCKET is set
  uint64_t watchdog_usec() const { return watchdog_usec_; }  // 0: no watchdog requested

  // Starts the thread (no-op when inactive). Polls every half watchdog
  // interval, or every 100 ms for READY=1 alone.
  void start();
  // STOPPING=1 with `status`, then joins. Idempotent.
  void stop(const std::string& status);

  // One check, what the thread does each period: READY=1 on the first beat,
  // WATCHDOG=1 when the beats moved. Public for tests. Returns what it sent
  // ("" for nothing).
  std::string poll_once();

 private:
  void run();
  const std::atomic<int64_t>& beats_;
  bool active_ = false;
  uint64_t watchdog_usec_ = 0;
  bool ready_sent_ = false;
  int64_t last_beats_ = 0;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  bool stopped_ = false;
};

}  // namespace rigctl
