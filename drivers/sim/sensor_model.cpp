#include "drivers/sim/sensor_model.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

SensorModel::SensorModel(const SensorSpec& spec) : spec_(spec) {
  if (spec.bits > 0) lsb_ = (spec.range_max - spec.range_min) / std::ldexp(1.0, spec.bits);
}

double SensorModel::measure(double truth, std::mt19937_64& rng) const noexcept {
  double v = truth + spec_.offset;
  if (spec_.noise_sd > 0.0) v += spec_.noise_sd * standard_normal(rng);
  if (spec_.bits > 0) {
    v = std::clamp(v, spec_.range_min, spec_.range_max);
    v = spec_.range_min + std::round((v - spec_.range_min) / lsb_) * lsb_;
  }
  return v;
}

}  // namespace rigctl
