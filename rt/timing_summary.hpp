// Summary of the loop's timing statistics, cheap to copy into telemetry.
#pragma once

#include <cstdint>

#include "rt/tick_stages.hpp"

namespace rigctl {

struct DistributionSummary {
  int64_t count = 0;
  int64_t min_ns = 0;
  int64_t max_ns = 0;
  double mean_ns = 0.0;
  int64_t p50_ns = 0;
  int64_t p99_ns = 0;
  int64_t p999_ns = 0;
};

struct TimingSummary {
  int64_t period_ns = 0;
  int64_t ticks = 0;         // ticks executed
  int64_t overruns = 0;      // ticks whose work ended after the next deadline
  int64_t missed_ticks = 0;  // periods skipped under the skip policy
  DistributionSummary wakeup_latency;  // wake-up time minus deadline
  DistributionSummary compute;         // wake-up to hand-off done, one tick
  TickStageSummary stages;             // where the compute time went, per step of the tick
};

}  // namespace rigctl
