#include "tools/iterate/gain_adaptation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rigctl {

namespace {

// A band carrying less than 0.1 % of the record's energy was not measured
// well enough to set its gain from (the noise's share there is large).
constexpr double kMeasuredShare = 1e-3;
// 90 % of the optimal gain: a little short of it, so that the ratio's own
// error (friction makes the rig's gain depend on the level) does not
// overshoot.
constexpr double kGainShare = 0.9;
// alpha between 0.1 (a band still moves) and 1.2 (a rig up to 25 % weaker
// than its model is met; beyond, more would amplify the ratio's error).
constexpr double kGainMin = 0.1, kGainMax = 1.2;
// An update that leaves more than 80 % of the error (the rig's phase more
// than about 50 degrees from the model's) does more harm than good where
// the estimate is off: the band is gated.
constexpr double kGateResidual = 0.8;

}  // namespace

GainUpdate adapt_gain(const std::vector<std::complex<double>>& ratio, const std::vector<double>& energy,
                      const std::vector<double>& current) {
  GainUpdate u{current, {}};
  // Band 0 lies below the band (gain_bands): a lead-in ramp's slow motion,
  // which the loop follows; it keeps its gain and does not count in the
  // share (its energy would make every band of the road look unmeasured).
  const double total = energy.empty() ? 0.0 : std::accumulate(energy.begin() + 1, energy.end(), 0.0);
  if (!(total > 0.0)) return u;
  for (std::size_t b = 1; b < current.size() && b < ratio.size(); ++b) {
    if (energy[b] < kMeasuredShare * total || current[b] == 0.0) continue;
    const std::complex<double> r = ratio[b];
    const double best = r.real() > 0.0 ? r.real() / std::norm(r) : 0.0;
    const double alpha = std::clamp(kGainShare * best, kGainMin, kGainMax);
    if (!(r.real() > 0.0) || std::abs(1.0 - alpha * r) > kGateResidual) {
      u.gain[b] = 0.0;
      u.gated.push_back(b);
      continue;
    }
    u.gain[b] = alpha;
  }
  return u;
}

}  // namespace rigctl
