#include "plant/pneumatic_rotary/coulomb_friction.hpp"

#include <algorithm>

namespace rigctl {

double coulomb_brake_level(const CoulombBrakeParams& p, double max_torque) {
  return p.enabled ? std::max(0.0, p.level * max_torque) : 0.0;
}

int breakaway_direction(double residual, double capacity) {
  if (residual > capacity) return 1;
  if (residual < -capacity) return -1;
  return 0;
}

double holding_share(double residual, double capacity, double total_capacity) {
  if (!(total_capacity > 0.0)) return 0.0;
  return residual * (capacity / total_capacity);
}

}  // namespace rigctl
