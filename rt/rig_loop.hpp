// The fixed-period control loop. One tick:
//   sleep to the absolute deadline -> driver.read -> limit check -> setpoint
//   -> controller -> driver.write -> telemetry record into a lock-free queue
// Nothing on this path allocates, locks, logs or formats; events are codes
// that the publisher thread turns into text.
#pragma once

#include <atomic>
#include <cstdint>

#include "drivers/driver.hpp"
#include "rt/controller.hpp"
#include "rt/limit_check.hpp"
#include "rt/loop_clock.hpp"
#include "rt/setpoint_profile.hpp"
#include "rt/telemetry_sink.hpp"
#include "rt/timing_stats.hpp"

namespace rigctl {

struct LoopOptions {
  int64_t period_ns = 2'500'000;
  OverrunPolicy overrun_policy = OverrunPolicy::kSkip;
  int64_t max_ticks = 0;          // run length; the run ends after this many ticks
  int64_t timing_every_ticks = 400;  // publish timing statistics this often (1 s at 2.5 ms)
  int start_from_input = -1;  // >= 0: the profile starts from this input's first value (bumpless start)
};

struct LoopResult {
  int64_t ticks = 0;
  RigState final_state = RigState::kStopped;
  Event end_event;  // why the run ended
  TimingSummary timing;
  int64_t dropped_records = 0;
};

class RigLoop {
 public:
  RigLoop(Driver& driver, Controller& controller, FilteredProfile& profile, const LimitCheck& limits,
          TelemetrySink& telemetry, LoopClock& clock, const LoopOptions& options);

  // Runs until max_ticks, a fault, or stop_requested becomes true (set from a
  // signal handler). The driver is made safe on every way out.
  LoopResult run(const std::atomic<bool>& stop_requested);

  const TimingStats& timing() const { return timing_; }

 private:
  void emit(TelemetryRecord& record, bool with_timing) noexcept;

  Driver& driver_;
  Controller& controller_;
  FilteredProfile& profile_;
  const LimitCheck& limits_;
  TelemetrySink& telemetry_;
  LoopClock& clock_;
  LoopOptions options_;
  TimingStats timing_;
  int64_t dropped_ = 0;
};

}  // namespace rigctl
