#include "plant/quarter_car/quarter_car_step_size.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

double quarter_car_fastest_rate(const QuarterCarParams& p) {
  const double stroke = p.stroke_max - p.stroke_min;
  const double a1 = p.area_cap * p.area_cap, a2 = p.area_rod * p.area_rod;
  // At the end cap the cap chamber is at its dead volume, at the head the rod chamber.
  const double at_cap = a1 / p.dead_volume_cap + a2 / (p.dead_volume_rod + p.area_rod * stroke);
  const double at_head = a1 / (p.dead_volume_cap + p.area_cap * stroke) + a2 / p.dead_volume_rod;
  const double stiffness = p.bulk_modulus * std::max(at_cap, at_head) + p.end_stop_stiffness + p.tyre_stiffness;
  return std::sqrt(stiffness / p.mass_rod);
}

int quarter_car_substeps(const QuarterCarParams& p, double fastest_rate, double dt) {
  if (p.substeps > 0) return p.substeps;
  const double n = std::ceil(dt * fastest_rate / kQuarterCarStepLimit);
  return static_cast<int>(std::clamp(n, 1.0, 100000.0));
}

int quarter_car_substeps(const QuarterCarParams& p, double dt) {
  return quarter_car_substeps(p, quarter_car_fastest_rate(p), dt);
}

}  // namespace rigctl
