// A transducer's transport delay in the simulated driver: a fixed ring of the
// true signal at the control period, read back at t - delay with cubic
// (Catmull-Rom) interpolation between samples. Cubic, not linear, so that the
// diagnosis (which fits a linearly interpolated delay) meets a delay that is
// not its own formula. Allocation-free after construction.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace rigctl {

class DelayLine {
 public:
  DelayLine() = default;
  // delay_s >= 0; period_s > 0.
  DelayLine(double delay_s, double period_s)
      : shift_(delay_s / period_s), ring_(static_cast<std::size_t>(std::ceil(delay_s / period_s)) + 4, 0.0) {}

  bool active() const noexcept { return shift_ > 0.0; }

  // Pushes the present true value and returns the delayed one. Before the
  // history is long enough the first value stands for the past (the rig was at rest).
  double push(double x) noexcept {
    if (count_ == 0) std::fill(ring_.begin(), ring_.end(), x);
    head_ = (head_ + 1) % ring_.size();
    ring_[head_] = x;
    ++count_;
    const double s = shift_;
    const auto k = static_cast<std::size_t>(s);  // whole samples back
    const double a = s - static_cast<double>(k);  // fraction further back
    // Points at k-1, k, k+1, k+2 samples back; interpolate between k and k+1.
    const double p0 = back(k == 0 ? 0 : k - 1), p1 = back(k), p2 = back(k + 1), p3 = back(k + 2);
    const double b = a;  // parameter from p1 (b = 0) to p2 (b = 1)
    return 0.5 * (2.0 * p1 + (-p0 + p2) * b + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * b * b +
                  (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * b * b * b);
  }

 private:
  double back(std::size_t k) const noexcept { return ring_[(head_ + ring_.size() - k) % ring_.size()]; }

  double shift_ = 0.0;
  std::vector<double> ring_{0.0};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
};

}  // namespace rigctl
