#include "tools/tune/margins.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace rigctl {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = 180.0 / std::numbers::pi;

// Linear interpolation in log frequency between grid points i and i + 1
// where y crosses `level`.
double crossing(const std::vector<double>& f, const std::vector<double>& y, std::size_t i, double level) {
  const double t = (level - y[i]) / (y[i + 1] - y[i]);
  return std::exp(std::log(f[i]) + t * (std::log(f[i + 1]) - std::log(f[i])));
}

double interpolate(const std::vector<double>& f, const std::vector<double>& y, double at) {
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    if (at >= f[i] && at <= f[i + 1]) {
      const double t = (std::log(at) - std::log(f[i])) / (std::log(f[i + 1]) - std::log(f[i]));
      return y[i] + t * (y[i + 1] - y[i]);
    }
  }
  return kNaN;
}

}  // namespace

std::vector<double> unwrapped_phase_deg(const std::vector<std::complex<double>>& l) {
  std::vector<double> out;
  for (const auto& z : l) {
    double p = std::arg(z) * kDeg;
    if (out.empty()) {
      if (p > 0.0) p -= 360.0;
    } else {
      while (p - out.back() > 180.0) p -= 360.0;
      while (p - out.back() < -180.0) p += 360.0;
    }
    out.push_back(p);
  }
  return out;
}

Margins loop_margins(const std::vector<double>& f, const std::vector<std::complex<double>>& l) {
  Margins m{kNaN, kNaN, kNaN, kNaN, false, 0.0};
  std::vector<double> db;
  for (const auto& z : l) {
    db.push_back(20.0 * std::log10(std::abs(z)));
    m.peak_sensitivity = std::max(m.peak_sensitivity, 1.0 / std::abs(1.0 + z));
  }
  const auto phase = unwrapped_phase_deg(l);
  std::size_t after = 0;
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    if (db[i] >= 0.0 && db[i + 1] < 0.0) {
      m.crossover_hz = crossing(f, db, i, 0.0);
      m.phase_margin_deg = 180.0 + interpolate(f, phase, m.crossover_hz);
      after = i;
      break;
    }
  }
  if (std::isnan(m.crossover_hz)) return m;
  m.gain_margin_db = -db.back();
  m.gain_margin_beyond_band = true;
  for (std::size_t i = after; i + 1 < f.size(); ++i) {
    const double line = -180.0;
    if (phase[i] > line && phase[i + 1] <= line && f[i + 1] > m.crossover_hz) {
      m.phase_crossover_hz = crossing(f, phase, i, line);
      m.gain_margin_db = -interpolate(f, db, m.phase_crossover_hz);
      m.gain_margin_beyond_band = false;
      break;
    }
  }
  return m;
}

}  // namespace rigctl
