// Fixed-memory histogram of durations, for the real-time path: recording is a
// bounds check and an increment; percentiles are computed off the hot path.
#pragma once

#include <cstdint>
#include <vector>

#include "rt/timing_summary.hpp"

namespace rigctl {

class DurationHistogram {
 public:
  // Bins of width bin_ns from 0 to bin_ns * bins; values outside go to the
  // first or last bin but min and max stay exact. Allocates here only.
  DurationHistogram(int64_t bin_ns, int bins);

  void record(int64_t ns) noexcept;
  void clear() noexcept;

  // p in [0, 1]. The upper edge of the bin holding the p-quantile (so a
  // reported p99 is never below the true one), clamped to [min, max].
  int64_t percentile(double p) const noexcept;
  DistributionSummary summary() const noexcept;

  int64_t count() const noexcept { return count_; }
  int64_t bin_ns() const noexcept { return bin_ns_; }

 private:
  int64_t bin_ns_;
  std::vector<uint32_t> counts_;
  int64_t count_ = 0;
  int64_t min_ = 0;
  int64_t max_ = 0;
  double sum_ = 0.0;
};

}  // namespace rigctl
