#include "plant/quarter_car/hidden_effect_laws.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rigctl {

double seal_friction_force(const QuarterCarHiddenEffects& h, double v, double p1, double p2) {
  const double fc = h.seal_preload + h.seal_pressure_coefficient * std::max(0.0, p1 + p2);
  if (fc == 0.0 && h.seal_viscous == 0.0) return 0.0;
  const double fbrk = h.seal_breakaway_ratio * fc;
  if (h.seal_form == 1) {
    constexpr double kCoulombBand = 0.001;  // [m/s] a steep step, far sharper than the diagnosis' 20 mm/s
    return (fc + (fbrk - fc) * std::exp(-std::abs(v) / h.seal_breakaway_velocity)) * std::tanh(v / kCoulombBand) +
           h.seal_viscous * v;
  }
  const double v_st = h.seal_breakaway_velocity * std::sqrt(2.0), v_coul = h.seal_breakaway_velocity / 2.0;
  return std::sqrt(2.0 * std::numbers::e) * (fbrk - fc) * std::exp(-(v / v_st) * (v / v_st)) * v / v_st +
         fc * std::tanh(v / v_coul) + h.seal_viscous * v;
}

double mixture_bulk_modulus(double e, double alpha, double n, double p) {
  if (alpha <= 0.0) return e;
  constexpr double pa = 101325.0;  // atmospheric [Pa abs]
  const double pabs = std::max(pa + p, 1e3);
  const double ratio = std::pow(pa / pabs, 1.0 / n);
  return e * (1.0 + alpha * ratio) / (1.0 + alpha * e * ratio / (n * pabs));
}

double damper_force(double bd, const QuarterCarHiddenEffects& h, double v) {
  if (v >= 0.0) return bd * h.damper_compression_factor * v;
  return bd * h.damper_rebound_factor * (1.0 + h.damper_rebound_progression * std::abs(v)) * v;
}

namespace {
double lugre_g(const LugreLevels& l, double v) {
  const double r = v / l.stribeck_velocity;
  return std::max(1e-6, l.coulomb + (l.breakaway - l.coulomb) * std::exp(-r * r));
}
}  // namespace

double lugre_force(const LugreLevels& l, double z, double v) {
  const double zdot = v - l.sigma0 * std::abs(v) * z / lugre_g(l, v);
  return l.sigma0 * z + l.sigma1 * zdot + l.viscous * v;
}

double lugre_advance(const LugreLevels& l, double z, double v, double h) {
  if (v == 0.0) return z;
  const double g = lugre_g(l, v);
  const double z_ss = std::copysign(g / l.sigma0, v);
  return z_ss + (z - z_ss) * std::exp(-l.sigma0 * std::abs(v) * h / g);
}

}  // namespace rigctl
