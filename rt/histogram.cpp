#include "rt/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rigctl {

DurationHistogram::DurationHistogram(int64_t bin_ns, int bins) : bin_ns_(bin_ns) {
  if (bin_ns <= 0 || bins <= 0) throw std::invalid_argument("histogram needs positive bin width and count");
  counts_.assign(static_cast<std::size_t>(bins), 0);
}

void DurationHistogram::record(int64_t ns) noexcept {
  const int64_t last = static_cast<int64_t>(counts_.size()) - 1;
  const int64_t bin = std::clamp<int64_t>(ns / bin_ns_, 0, last);
  ++counts_[static_cast<std::size_t>(bin)];
  if (count_ == 0 || ns < min_) min_ = ns;
  if (count_ == 0 || ns > max_) max_ = ns;
  sum_ += static_cast<double>(ns);
  ++count_;
}

void DurationHistogram::clear() noexcept {
  std::fill(counts_.begin(), counts_.end(), 0u);
  count_ = 0;
  min_ = max_ = 0;
  sum_ = 0.0;
}

int64_t DurationHistogram::percentile(double p) const noexcept {
  if (count_ == 0) return 0;
  // Rank of the p-quantile, 1-based (nearest-rank definition).
  const auto rank = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(p * static_cast<double>(count_))));
  int64_t seen = 0;
  for (std::size_t i = 0; i < counts_.size(); ++i) {
    seen += counts_[i];
    if (seen >= rank) {
      if (i + 1 == counts_.size()) return max_;  // the overflow bin has no upper edge
      const int64_t upper = static_cast<int64_t>(i + 1) * bin_ns_;
      return std::clamp(upper, min_, max_);
    }
  }
  return max_;
}

DistributionSummary DurationHistogram::summary() const noexcept {
  DistributionSummary s;
  s.count = count_;
  s.min_ns = min_;
  s.max_ns = max_;
  s.mean_ns = count_ > 0 ? sum_ / static_cast<double>(count_) : 0.0;
  s.p50_ns = percentile(0.50);
  s.p99_ns = percentile(0.99);
  s.p999_ns = percentile(0.999);
  return s;
}

}  // namespace rigctl
