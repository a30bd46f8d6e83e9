// The Foxglove server's refusals: counted per kind, and handed to the
// run's event log at most kLinesPerSecond a second (the rest counted and
// summarised), so that a flood of bad requests or connections cannot fill
// the disk. Thread-safe.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>

#include "rt/comms/rate_limit.hpp"

namespace rigctl::foxglove {

// code: what was refused ("origin", "too_many_clients", "queue_overflow",
// "bad_request", ...); text: one line naming the client and why.
using RefusalHandler = std::function<void(const std::string& code, const std::string& text)>;

class RefusalLog {
 public:
  // As many as the command receiver logs (rt/comms/command_intake.hpp).
  static constexpr int kLinesPerSecond = 20;

  void set_handler(RefusalHandler handler) {
    std::lock_guard<std::mutex> lock(mu_);
    handler_ = std::move(handler);
  }
  void refuse(const std::string& code, const std::string& text) {
    std::lock_guard<std::mutex> lock(mu_);
    ++counts_[code];
    if (!handler_) return;
    const int64_t now_us =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
    uint64_t suppressed = 0;
    const bool write = limit_.admit(now_us, &suppressed);
    if (suppressed > 0) handler_("suppressed", std::to_string(suppressed) + " more client refusals not logged individually");
    if (write) handler_(code, text);
  }
  std::map<std::string, int64_t> counts() const {
    std::lock_guard<std::mutex> lock(mu_);
    return counts_;
  }

 private:
  mutable std::mutex mu_;
  RefusalHandler handler_;
  LogRateLimit limit_{kLinesPerSecond};
  std::map<std::string, int64_t> counts_;
};

}  // namespace rigctl::foxglove
