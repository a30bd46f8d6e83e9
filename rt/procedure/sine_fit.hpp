// The fundamental of one cycle of a response by least squares on running
// sums: y = mean + a sin(theta) + b cos(theta), theta the wanted phase of
// each tick. Exact for a pure sine whatever the cycle's number of ticks
// (a plain Fourier sum over a cycle that is not a whole number of ticks is
// off by up to f*Ts: 4 % at 15 Hz and 2.5 ms). Nine sums per tick, a 3x3
// solve per cycle: no allocation, no loop over the cycle's samples.
#pragma once

#include <cmath>

namespace rigctl {

struct Fundamental {
  bool valid = false;
  double mean = 0.0;
  double amplitude = 0.0;
  double phase = 0.0;  // [rad], y = mean + amplitude sin(theta + phase)
};

class SineFit {
 public:
  void reset() noexcept { *this = SineFit{}; }
  void add(double theta, double y) noexcept {
    const double s = std::sin(theta), c = std::cos(theta);
    n_ += 1.0;
    s_ += s;
    c_ += c;
    ss_ += s * s;
    cc_ += c * c;
    sc_ += s * c;
    y_ += y;
    ys_ += y * s;
    yc_ += y * c;
  }
  Fundamental solve() const noexcept;

 private:
  double n_ = 0, s_ = 0, c_ = 0, ss_ = 0, cc_ = 0, sc_ = 0, y_ = 0, ys_ = 0, yc_ = 0;
};

// Wraps an angle into (-pi, pi].
inline double wrap_pi(double a) noexcept {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

}  // namespace rigctl
