// A transducer's signal-conditioning filter in the simulated driver: a
// second-order Butterworth low-pass (bilinear transform at the control
// period, the cut-off pre-warped) on the true signal before noise and
// quantisation. It is the other physical form of a "sensor delay"
// (tools/hidden_effects): at low frequency its phase lag is that of a delay
// of sqrt(2) / (2 pi f_c), but its magnitude rolls off and its phase
// saturates, so it is not the pure delay the diagnosis fits.
// Allocation-free.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rigctl {

class ConditioningFilter {
 public:
  ConditioningFilter() = default;
  // cutoff_hz > 0 makes an active filter; 0 is a pass-through.
  ConditioningFilter(double cutoff_hz, double period_s) {
    if (!(cutoff_hz > 0.0) || !(period_s > 0.0)) return;
    const double fc = std::min(cutoff_hz, 0.45 / period_s);
    const double k = std::tan(std::numbers::pi * fc * period_s);
    const double q = std::numbers::sqrt2;  // 1 / Q of a Butterworth pair
    const double norm = 1.0 / (1.0 + q * k + k * k);
    b0_ = k * k * norm;
    b1_ = 2.0 * b0_;
    b2_ = b0_;
    a1_ = 2.0 * (k * k - 1.0) * norm;
    a2_ = (1.0 - q * k + k * k) * norm;
    active_ = true;
  }

  bool active() const noexcept { return active_; }

  // Low-frequency group delay [s] of a Butterworth pair: sqrt(2) / (2 pi f_c).
  static double group_delay(double cutoff_hz) { return std::numbers::sqrt2 / (2.0 * std::numbers::pi * cutoff_hz); }
  // The cut-off whose low-frequency group delay is `delay_s`.
  static double cutoff_for_delay(double delay_s) { return std::numbers::sqrt2 / (2.0 * std::numbers::pi * delay_s); }

  // Filters the present true value. The first call settles the filter at it
  // (the rig was at rest before the run).
  double push(double x) noexcept {
    if (!started_) {
      x1_ = x2_ = x;
      y1_ = y2_ = x;
      started_ = true;
    }
    const double y = b0_ * x + b1_ * x1_ + b2_ * x2_ - a1_ * y1_ - a2_ * y2_;
    x2_ = x1_;
    x1_ = x;
    y2_ = y1_;
    y1_ = y;
    return y;
  }

 private:
  bool active_ = false, started_ = false;
  double b0_ = 1.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;
  double x1_ = 0.0, x2_ = 0.0, y1_ = 0.0, y2_ = 0.0;
};

}  // namespace rigctl
