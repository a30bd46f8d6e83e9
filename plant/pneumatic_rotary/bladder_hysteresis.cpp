#include "plant/pneumatic_rotary/bladder_hysteresis.hpp"

#include <algorithm>

namespace rigctl {

BladderHysteresisLevels bladder_hysteresis_levels(const BladderHysteresisParams& p, double max_torque) {
  BladderHysteresisLevels l;
  if (!p.enabled) return l;
  l.half_width = std::max(0.0, p.level * max_torque);
  double fraction = std::clamp(p.step_fraction, 0.0, 1.0);
  // A vertical ramp is a step: fold it into the step part rather than carry
  // an infinite stiffness.
  if (!(p.boundary_angle > 0.0)) fraction = 1.0;
  l.step = fraction * l.half_width;
  l.elastic_limit = l.half_width - l.step;
  l.stiffness = l.elastic_limit > 0.0 ? 2.0 * l.elastic_limit / p.boundary_angle : 0.0;
  return l;
}

double bladder_elastic_torque(const BladderHysteresisLevels& l, const HysteresisAnchor& anchor, double theta) {
  return std::clamp(anchor.torque + l.stiffness * (theta - anchor.theta), -l.elastic_limit, l.elastic_limit);
}

void BladderHysteresis::reset(double theta) {
  anchor_ = {theta, 0.0};
  last_theta_ = theta;
  elastic_ = 0.0;
  direction_ = 0;
}

double BladderHysteresis::update(double theta) {
  const double d = theta - last_theta_;
  if (d != 0.0) {
    const int dir = d > 0.0 ? 1 : -1;
    if (dir != direction_) anchor_ = {last_theta_, elastic_};
    direction_ = dir;
    elastic_ = bladder_elastic_torque(levels_, anchor_, theta);
  }
  last_theta_ = theta;
  return torque();
}

}  // namespace rigctl
