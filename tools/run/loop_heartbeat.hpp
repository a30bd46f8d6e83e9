// A telemetry sink in front of the real one that counts the records the loop
// hands over: one per tick, so the count advancing means the loop is alive
// and ticking. The service watchdog (tools/run/service_notify.hpp) reads it from
// its own thread; the loop pays one relaxed atomic store per tick.
#pragma once

#include <atomic>
#include <cstdint>

#include "rt/comms/telemetry_sink.hpp"

namespace rigctl {

class LoopHeartbeat final : public TelemetrySink {
 public:
  explicit LoopHeartbeat(TelemetrySink& inner) : inner_(inner) {}

  bool push(const TelemetryRecord& record) noexcept override {
    // Single writer (the loop): load + store, no read-modify-write needed.
    beats_.store(beats_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    return inner_.push(record);
  }

  // Records pushed so far; any thread.
  const std::atomic<int64_t>& beats() const { return beats_; }

 private:
  TelemetrySink& inner_;
  std::atomic<int64_t> beats_{0};
};

}  // namespace rigctl
