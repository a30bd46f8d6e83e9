#include "tools/iterate/test_window.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

// A target departs from its lead-in where its content above kDetectHz
// first reaches 15 % of its peak: a lead-in ramp's content lies below it
// (a 3.5 s half-cosine ramp of 80 mm leaves well under a millimetre above
// 2 Hz, a linear ramp's corners about 2 mm at 25 mm/s), a road's first
// bumps and its random content above it do not.
constexpr double kDetectHz = 2.0;
constexpr double kDepartureShare = 0.15;

// A smooth high-pass (fourth-order magnitude, no phase): no ringing of its
// own around a ramp's corners, as a brick-wall edge would have.
std::vector<double> detail(const std::vector<double>& x, double dt) {
  return filtered(x, dt, [](double f) {
    const double r = std::pow(f / kDetectHz, 4);
    return std::complex<double>(r / (1.0 + r), 0.0);
  });
}

double ramp(double x) { return 0.5 - 0.5 * std::cos(std::numbers::pi * std::clamp(x, 0.0, 1.0)); }

}  // namespace

TestWindow find_test_window(const std::vector<double>& target, double dt) {
  TestWindow w{0, target.size(), "whole record"};
  if (target.size() < 2) return w;
  const std::vector<double> band = detail(target, dt);
  double peak = 0.0;
  for (double v : band) peak = std::max(peak, std::abs(v));
  if (!(peak > 0.0)) return w;
  const double level = kDepartureShare * peak;
  std::size_t first = 0, last = band.size() - 1;
  while (first < last && std::abs(band[first]) < level) ++first;
  while (last > first && std::abs(band[last]) < level) --last;
  w.begin = first;
  w.end = last + 1;
  w.source = (first == 0 && last + 1 == target.size()) ? "whole record" : "lead-in/lead-out";
  return w;
}

std::pair<double, double> parse_time_window(const std::string& text) {
  const auto colon = text.find(':');
  const auto number = [&](const std::string& part) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (part.empty() || *end != '\0' || !std::isfinite(v)) {
      throw std::invalid_argument("--window '" + text + "': expected T0:T1 in seconds, e.g. 5:20");
    }
    return v;
  };
  if (colon == std::string::npos) number("");
  return {number(text.substr(0, colon)), number(text.substr(colon + 1))};
}

TestWindow window_from_times(double t0_s, double t1_s, std::size_t n, double dt) {
  const double span = static_cast<double>(n) * dt;
  if (!(t0_s >= 0.0 && t1_s > t0_s && t1_s <= span + 0.5 * dt)) {
    throw std::invalid_argument("--window " + std::to_string(t0_s) + ":" + std::to_string(t1_s) +
                                ": needs 0 <= T0 < T1 <= " + std::to_string(span) + " s (the target's length)");
  }
  TestWindow w;
  w.begin = static_cast<std::size_t>(std::llround(t0_s / dt));
  w.end = std::min(n, static_cast<std::size_t>(std::llround(t1_s / dt)));
  w.source = "--window";
  if (w.end <= w.begin + 1) throw std::invalid_argument("--window: shorter than two samples");
  return w;
}

std::vector<double> correction_weight(const TestWindow& window, const std::vector<double>& target, double dt,
                                      double lead_s, double min_ramp_s) {
  const std::size_t n = target.size();
  std::vector<double> w(n, 1.0);
  if (n == 0) return w;
  // The holds at the ends: the target within a 10^-4 of its range of its
  // first (last) value (8 um of an 80 mm ramp: a resampled hold's ripple).
  const auto [lo, hi] = std::minmax_element(target.begin(), target.end());
  const double still = 1e-4 * (*hi - *lo);
  std::size_t hold_in = 0, hold_out = 0;
  while (hold_in < window.begin && std::abs(target[hold_in] - target.front()) <= still) ++hold_in;
  while (hold_out + window.end < n && std::abs(target[n - 1 - hold_out] - target.back()) <= still) ++hold_out;
  const double lead = lead_s / dt, min_ramp = std::max(1.0, min_ramp_s / dt);
  const double rise = std::max(min_ramp, static_cast<double>(window.begin) - lead - static_cast<double>(hold_in));
  const double fall = std::max(min_ramp, static_cast<double>(n - window.end) - lead - static_cast<double>(hold_out));
  for (std::size_t i = 0; i < n; ++i) {
    const double from_start = static_cast<double>(i) - static_cast<double>(hold_in);
    const double to_end = static_cast<double>(n - 1 - i) - static_cast<double>(hold_out);
    w[i] = std::min(ramp(from_start / rise), ramp(to_end / fall));
  }
  return w;
}

}  // namespace rigctl
