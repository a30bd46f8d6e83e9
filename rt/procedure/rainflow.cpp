#include "rt/procedure/rainflow.hpp"

#include <cmath>

namespace rigctl {

void RainflowCounter::reset() noexcept {
  size_ = 0;
  started_ = false;
  candidate_ = 0.0;
  direction_ = 0;
  overflowed_ = false;
}

// A sample either extends the present excursion (a new candidate extreme),
// turns it (the candidate is confirmed as a turning point) or repeats the
// candidate (nothing: a flat top is one turning point).
void RainflowCounter::push(double x, CycleSink& sink) noexcept {
  if (!started_) {
    // The history's first point is a turning point (ASTM: the starting point S).
    started_ = true;
    candidate_ = x;
    add_turning_point(x, stack_, size_, overflowed_, sink);
    return;
  }
  if (x == candidate_) return;
  const int step = x > candidate_ ? 1 : -1;
  if (direction_ == 0) {
    direction_ = step;  // the first move away from the starting point
    candidate_ = x;
    return;
  }
  if (step == direction_) {
    candidate_ = x;
    return;
  }
  add_turning_point(candidate_, stack_, size_, overflowed_, sink);
  direction_ = step;
  candidate_ = x;
}

// ASTM E1049 5.4.4 steps 2-5. The starting point S is always the stack's
// first point: step 5 discards the first point and S moves to the next, and
// step 4 discards two points that are never the first.
void RainflowCounter::add_turning_point(double x, std::array<double, kStackCapacity>& stack, std::size_t& size,
                                        bool& overflowed, CycleSink& sink) noexcept {
  if (size == kStackCapacity) {
    // Full: the oldest range as a half cycle, S moves on (see the header).
    sink.on_cycle(RainflowCycle{stack[0], stack[1], 0.5});
    for (std::size_t i = 1; i < size; ++i) stack[i - 1] = stack[i];
    --size;
    overflowed = true;
  }
  stack[size++] = x;
  while (size >= 3) {
    const double x_range = std::fabs(stack[size - 1] - stack[size - 2]);
    const double y_range = std::fabs(stack[size - 2] - stack[size - 3]);
    if (x_range < y_range) return;  // step 3: read the next point
    if (size == 3) {
      // Step 5: Y contains S: a half cycle, S moves to Y's second point.
      sink.on_cycle(RainflowCycle{stack[0], stack[1], 0.5});
      stack[0] = stack[1];
      stack[1] = stack[2];
      size = 2;
    } else {
      // Step 4: a full cycle; Y's two points leave the stack.
      sink.on_cycle(RainflowCycle{stack[size - 3], stack[size - 2], 1.0});
      stack[size - 3] = stack[size - 1];
      size -= 2;
    }
  }
}

void RainflowCounter::residue_half_cycles(CycleSink& sink) const noexcept {
  if (!started_) return;
  // A copy: the last sample is the history's last turning point only if the
  // history ends here; the live count must not take it as one.
  std::array<double, kStackCapacity> stack = stack_;
  std::size_t size = size_;
  bool overflowed = overflowed_;
  if (size == 0 || candidate_ != stack[size - 1]) add_turning_point(candidate_, stack, size, overflowed, sink);
  for (std::size_t i = 1; i < size; ++i) sink.on_cycle(RainflowCycle{stack[i - 1], stack[i], 0.5});  // step 6
}

bool RainflowCounter::restore(const double* points, std::size_t n, bool has_pending, double pending,
                              int direction) noexcept {
  if (n > kStackCapacity || (has_pending && n == 0)) return false;
  reset();
  for (std::size_t i = 0; i < n; ++i) stack_[i] = points[i];
  size_ = n;
  started_ = has_pending;
  candidate_ = pending;
  direction_ = direction > 0 ? 1 : (direction < 0 ? -1 : 0);
  return true;
}

// ---- matrix

void RainflowMatrix::configure(double lo, double hi, double basquin_exponent, double reference_range) noexcept {
  d_.lo = lo;
  d_.hi = hi > lo ? hi : lo + 1.0;
  d_.exponent = basquin_exponent;
  d_.reference = reference_range > 0.0 ? reference_range : 1.0;
  reset();
}

void RainflowMatrix::reset() noexcept {
  for (auto& row : d_.counts) row.fill(0.0);
  d_.total = 0.0;
  d_.damage = 0.0;
}

std::size_t RainflowMatrix::bin(double x, double lo, double width) noexcept {
  const double i = std::floor((x - lo) / width);
  if (!(i > 0.0)) return 0;  // below, and NaN
  return i >= static_cast<double>(kBins) ? kBins - 1 : static_cast<std::size_t>(i);
}

void RainflowMatrix::on_cycle(const RainflowCycle& c) noexcept {
  d_.counts[bin(c.range(), 0.0, range_width())][bin(c.mean(), d_.lo, mean_width())] += c.count;
  d_.total += c.count;
  d_.damage += c.count * std::pow(c.range() / d_.reference, d_.exponent);
}

void RainflowMatrix::add(const RainflowMatrix& other) noexcept {
  for (std::size_t i = 0; i < kBins; ++i) {
    for (std::size_t j = 0; j < kBins; ++j) d_.counts[i][j] += other.d_.counts[i][j];
  }
  d_.total += other.d_.total;
  d_.damage += other.d_.damage;
}

void RainflowChannel::snapshot(RainflowMatrix& out) const noexcept {
  out = committed_;
  counter_.residue_half_cycles(out);
}

}  // namespace rigctl
