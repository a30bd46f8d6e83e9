// Loop timing: wake-up latency and compute-time distributions, overruns and
// the overrun policy that decides the next deadline. Pure arithmetic on
// timestamps handed in, so tests can inject them.
#pragma once

#include <cstdint>
#include <string_view>

#include "rt/histogram.hpp"
#include "rt/tick_stages.hpp"
#include "rt/timing_summary.hpp"

namespace rigctl {

// What to do when a tick ends after the next deadline.
enum class OverrunPolicy {
  // Drop the periods already missed and wait for the next deadline on the
  // original grid: the loop keeps its phase and never runs ticks back to back.
  // The usual choice for a servo loop, where a late command is worth less
  // than a regular one.
  kSkip,
  // Keep every deadline, running late ticks back to back until caught up.
  kCatchUp,
};

std::string_view to_string(OverrunPolicy p);
// Throws std::invalid_argument for anything but "skip" or "catch_up".
OverrunPolicy overrun_policy_from_string(std::string_view s);

class TimingStats {
 public:
  // Histograms cover 0 .. 2 periods in 1 us bins; beyond lands in the last bin
  // with min/max kept exact.
  TimingStats(int64_t period_ns, OverrunPolicy policy);

  // The loop woke for `deadline` at `wake`: a tick begins.
  void on_wake(int64_t deadline_ns, int64_t wake_ns) noexcept;
  // A step of the tick ended at `end` (it began where the previous one ended).
  void on_stage(TickStage stage, int64_t end_ns) noexcept { stages_.end(stage, end_ns); }
  // The tick that started at `start` finished at `end`; returns the deadline
  // of the next tick according to the policy, counting overruns and misses.
  int64_t on_done(int64_t deadline_ns, int64_t start_ns, int64_t end_ns) noexcept;

  TimingSummary summary() const noexcept;
  int64_t period_ns() const noexcept { return period_ns_; }
  int64_t overruns() const noexcept { return overruns_; }  // running total, cheap (limit detectors read it every tick)
  OverrunPolicy policy() const noexcept { return policy_; }

 private:
  int64_t period_ns_;
  OverrunPolicy policy_;
  DurationHistogram latency_;
  DurationHistogram compute_;
  TickStageTimes stages_;
  int64_t ticks_ = 0;
  int64_t overruns_ = 0;
  int64_t missed_ = 0;
};

}  // namespace rigctl
