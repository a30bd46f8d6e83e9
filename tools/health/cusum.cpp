#include "tools/health/cusum.hpp"

#include <algorithm>

namespace rigctl::health {

namespace {

// One side of the chart: its sum, where it last left zero, whether it has
// alarmed in this excursion.
struct Side {
  int direction = 0;
  double sum = 0.0;
  std::size_t start = 0;
  bool alarmed = false;

  void step(double z, std::size_t i, const CusumSettings& s) {
    const double before = sum;
    sum = std::max(0.0, sum + direction * z - s.k);
    if (before == 0.0 && sum > 0.0) start = i;  // an excursion begins here
    if (sum == 0.0) alarmed = false;            // back to the reference: re-armed
  }
};

// Where the change began: within the excursion (from the sum's last zero to
// the alarm), the maximum-likelihood start of a shift from the reference,
// the tau that maximises (sum of z from tau on)^2 / its length on the
// alarm's side. The sum's last zero alone can lie points before the change
// when noise had lifted it already. The size is the mean departure from tau on.
CusumAlarm describe(const Side& side, std::size_t i, const std::vector<CusumPoint>& points, double reference) {
  auto z = [&](std::size_t j) { return (points[j].x - reference) / points[j].sigma; };
  std::size_t best = i;
  double best_score = -1.0, tail = 0.0;
  for (std::size_t tau = i + 1; tau-- > side.start;) {
    tail += z(tau);
    const double score = side.direction * tail > 0.0 ? tail * tail / static_cast<double>(i - tau + 1) : 0.0;
    if (score > best_score) {
      best_score = score;
      best = tau;
    }
  }
  CusumAlarm a;
  a.raised_at = i;
  a.since = best;
  a.direction = side.direction;
  double shift = 0.0, zs = 0.0;
  for (std::size_t j = best; j <= i; ++j) {
    shift += points[j].x - reference;
    zs += z(j);
  }
  const double n = static_cast<double>(i - best + 1);
  a.mean_shift = shift / n;
  a.mean_shift_sigma = zs / n;
  return a;
}

}  // namespace

CusumTrace run_cusum(const std::vector<CusumPoint>& points, double reference, const CusumSettings& settings) {
  CusumTrace t;
  Side up{+1}, down{-1};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double z = points[i].sigma > 0.0 ? (points[i].x - reference) / points[i].sigma : 0.0;
    for (Side* side : {&up, &down}) {
      side->step(z, i, settings);
      if (side->sum > settings.h && !side->alarmed) {
        side->alarmed = true;
        t.alarms.push_back(describe(*side, i, points, reference));
      }
    }
    t.upper.push_back(up.sum);
    t.lower.push_back(down.sum);
  }
  return t;
}

}  // namespace rigctl::health
