#include "rt/procedure/sine_fit.hpp"

namespace rigctl {

// Cramer's rule on the normal equations
//   [n  s  c ] [m]   [y ]
//   [s  ss sc] [a] = [ys]
//   [c  sc cc] [b]   [yc]
Fundamental SineFit::solve() const noexcept {
  const auto det3 = [](double a11, double a12, double a13, double a21, double a22, double a23, double a31, double a32,
                       double a33) {
    return a11 * (a22 * a33 - a23 * a32) - a12 * (a21 * a33 - a23 * a31) + a13 * (a21 * a32 - a22 * a31);
  };
  Fundamental f;
  const double d = det3(n_, s_, c_, s_, ss_, sc_, c_, sc_, cc_);
  // Fewer than about four ticks a cycle leave the system near singular: no fit.
  if (n_ < 4.0 || !(std::fabs(d) > 1e-9 * n_ * n_ * n_)) return f;
  f.mean = det3(y_, s_, c_, ys_, ss_, sc_, yc_, sc_, cc_) / d;
  const double a = det3(n_, y_, c_, s_, ys_, sc_, c_, yc_, cc_) / d;
  const double b = det3(n_, s_, y_, s_, ss_, ys_, c_, sc_, yc_) / d;
  f.amplitude = std::hypot(a, b);
  f.phase = std::atan2(b, a);
  f.valid = true;
  return f;
}

}  // namespace rigctl
