// Running summary statistics of one channel (Welford's update: one pass,
// no sample kept, no cancellation of a large mean), so an hours-long log is
// summarised in constant memory.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "tools/catalog/run_entry.hpp"

namespace rigctl::catalog {

class ChannelSummary {
 public:
  void add(double v) {
    if (!std::isfinite(v)) return;  // an invalid sample is not a value of the channel
    ++n_;
    min_ = std::min(min_, v);
    max_ = std::max(max_, v);
    const double d = v - mean_;
    mean_ += d / static_cast<double>(n_);
    m2_ += d * (v - mean_);
    sum_sq_ += v * v;
  }
  ChannelStats stats(const std::string& channel, const std::string& unit) const {
    ChannelStats s{channel, unit, n_, 0.0, 0.0, 0.0, 0.0, 0.0};
    if (n_ == 0) return s;
    s.min = min_;
    s.max = max_;
    s.mean = mean_;
    s.std = n_ > 1 ? std::sqrt(m2_ / static_cast<double>(n_ - 1)) : 0.0;
    s.rms = std::sqrt(sum_sq_ / static_cast<double>(n_));
    return s;
  }

 private:
  int64_t n_ = 0;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = -std::numeric_limits<double>::infinity();
  double mean_ = 0.0, m2_ = 0.0, sum_sq_ = 0.0;
};

}  // namespace rigctl::catalog
