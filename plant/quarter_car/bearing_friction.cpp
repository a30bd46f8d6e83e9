#include "plant/quarter_car/bearing_friction.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

namespace {
// Below this the linkage would lie nearly flat against the rails and 1/tan
// explodes. Unreachable within the rig's stroke (the angle stays within about
// 62 +- 9 deg for +-50 mm of suspension travel); it only keeps F_n finite.
constexpr double kMinSinAngle = 0.05;
}  // namespace

double linkage_angle_change(const BearingFrictionParams& p, double deflection) {
  const double along = deflection * std::sin(p.construction_angle);
  const double rest = p.damper_free_length - along;
  double arg;
  if (std::abs(rest) > 1e-12) {
    arg = along / rest;
  } else {
    arg = along >= 0.0 ? 1.0 : -1.0;
  }
  return std::asin(std::clamp(arg, -1.0, 1.0));
}

BearingFrictionLevels bearing_friction_levels(const BearingFrictionParams& p, double body_weight,
                                              double suspension_force, double deflection) {
  BearingFrictionLevels out;
  const double angle = p.construction_angle - linkage_angle_change(p, deflection);
  // |cos|/|sin| rather than 1/tan: the magnitude of the side load does not
  // depend on which side of vertical the linkage leans.
  const double s = std::max(std::abs(std::sin(angle)), kMinSinAngle);
  out.normal = std::abs(body_weight + suspension_force) * std::abs(std::cos(angle)) / s;
  out.coulomb = p.coulomb_base + (p.normal_force_dependent ? p.normal_coefficient * out.normal : 0.0);
  out.breakaway = out.coulomb + p.stiction_excess;
  return out;
}

double sliding_friction(const BearingFrictionParams& p, const BearingFrictionLevels& levels,
                        int direction, double velocity) {
  double stribeck;
  if (p.stribeck_velocity > 0.0) {
    stribeck = std::exp(-std::pow(std::abs(velocity) / p.stribeck_velocity, p.stribeck_exponent));
  } else {
    stribeck = velocity == 0.0 ? 1.0 : 0.0;
  }
  const double dir = direction >= 0 ? 1.0 : -1.0;
  return dir * (levels.coulomb + (levels.breakaway - levels.coulomb) * stribeck) +
         p.viscous * velocity;
}

}  // namespace rigctl
