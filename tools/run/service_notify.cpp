#include "tools/run/service_notify.hpp"

#include <systemd/sd-daemon.h>

#include <chrono>
#include <cstdlib>

#include <spdlog/spdlog.h>

namespace rigctl {

ServiceNotifier::ServiceNotifier(const std::atomic<int64_t>& beats) : beats_(beats) {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  active_ = socket != nullptr && *socket != '\0';
  uint64_t usec = 0;
  // > 0: a watchdog is requested for this process (WATCHDOG_PID, if set, is ours).
  if (active_ && sd_watchdog_enabled(0, &usec) > 0) watchdog_usec_ = usec;
}

ServiceNotifier::~ServiceNotifier() { stop("stopping"); }

std::string ServiceNotifier::poll_once() {
  if (!active_) return "";
  const int64_t beats = beats_.load(std::memory_order_relaxed);
  std::string sent;
  if (!ready_sent_) {
    if (beats == 0) return "";  // the loop has not ticked yet
    ready_sent_ = true;
    sent = "READY=1\nSTATUS=control loop running";
  } else if (watchdog_usec_ > 0 && beats != last_beats_) {
    sent = "WATCHDOG=1";
  }
  last_beats_ = beats;
  if (sent.empty()) return "";
  const int rc = sd_notify(0, sent.c_str());
  if (rc < 0) spdlog::warn("systemd notify '{}' failed: error {}", sent.substr(0, sent.find('\n')), -rc);
  return sent;
}

void ServiceNotifier::start() {
  if (!active_ || thread_.joinable()) return;
  thread_ = std::thread([this] { run(); });
}

void ServiceNotifier::run() {
  // Half the watchdog interval: a ping that is late by one period still arrives in time.
  const auto period = watchdog_usec_ > 0 ? std::chrono::microseconds(watchdog_usec_ / 2) : std::chrono::microseconds(100'000);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    lock.unlock();
    poll_once();
    lock.lock();
    wake_.wait_for(lock, period, [this] { return stop_; });
  }
}

void ServiceNotifier::stop(const std::string& status) {
  if (stopped_) return;
  stopped_ = true;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  // Draining the logs after the loop takes a second or two without ticks:
  // STOPPING=1 tells systemd the pings end on purpose.
  if (active_) sd_notify(0, ("STOPPING=1\nSTATUS=" + status).c_str());
}

}  // namespace rigctl
