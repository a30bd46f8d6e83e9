#include "drivers/modbus/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rigctl {

namespace {

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// Piecewise-linear map through (xs[k], ys[k]) with xs sorted by `less`,
// extrapolating the end segments. std::lerp is exact at both ends of a
// segment, so breakpoints map exactly onto their partners.
template <typename Less>
double interpolate(const std::vector<double>& xs, const std::vector<double>& ys, double x, Less less) noexcept {
  if (std::isnan(x)) return std::numeric_limits<double>::quiet_NaN();
  const auto n = static_cast<std::ptrdiff_t>(xs.size());
  const std::ptrdiff_t upper = std::upper_bound(xs.begin(), xs.end(), x, less) - xs.begin();
  const std::ptrdiff_t k = std::clamp<std::ptrdiff_t>(upper - 1, 0, n - 2);
  const auto i = static_cast<std::size_t>(k);
  const double t = (x - xs[i]) / (xs[i + 1] - xs[i]);
  return std::lerp(ys[i], ys[i + 1], t);
}

}  // namespace

LinearCalibration::LinearCalibration(double gain, double offset) : gain_(gain), offset_(offset) {
  if (!std::isfinite(gain) || gain == 0.0) {
    throw std::invalid_argument("linear calibration: gain must be finite and non-zero, got " + num(gain));
  }
  if (!std::isfinite(offset)) {
    throw std::invalid_argument("linear calibration: offset must be finite, got " + num(offset));
  }
}

LinearCalibration LinearCalibration::from_points(double raw0, double si0, double raw1, double si1) {
  if (!std::isfinite(raw0) || !std::isfinite(si0) || !std::isfinite(raw1) || !std::isfinite(si1)) {
    throw std::invalid_argument("linear calibration: the two points must be finite");
  }
  if (raw0 == raw1) throw std::invalid_argument("linear calibration: the two points have the same raw value " + num(raw0));
  if (si0 == si1) throw std::invalid_argument("linear calibration: the two points have the same SI value " + num(si0));
  const double gain = (si1 - si0) / (raw1 - raw0);
  return LinearCalibration(gain, si0 - gain * raw0);
}

TableCalibration::TableCalibration(std::span<const CalibrationPoint> points) {
  raw_.reserve(points.size());
  si_.reserve(points.size());
  for (const auto& p : points) {
    raw_.push_back(p.raw);
    si_.push_back(p.si);
  }
  validate();
}

TableCalibration::TableCalibration(std::span<const double> raw, std::span<const double> si)
    : raw_(raw.begin(), raw.end()), si_(si.begin(), si.end()) {
  if (raw.size() != si.size()) {
    throw std::invalid_argument("calibration table: " + std::to_string(raw.size()) + " raw values but " +
                                std::to_string(si.size()) + " SI values");
  }
  validate();
}

void TableCalibration::validate() {
  if (raw_.size() < 2) {
    throw std::invalid_argument("calibration table: needs at least 2 points, got " + std::to_string(raw_.size()));
  }
  for (std::size_t i = 0; i < raw_.size(); ++i) {
    if (!std::isfinite(raw_[i]) || !std::isfinite(si_[i])) {
      throw std::invalid_argument("calibration table: point " + std::to_string(i) + " (raw " + num(raw_[i]) +
                                  ", SI " + num(si_[i]) + ") is not finite");
    }
  }
  for (std::size_t i = 1; i < raw_.size(); ++i) {
    if (!(raw_[i] > raw_[i - 1])) {
      throw std::invalid_argument("calibration table: point " + std::to_string(i) + ": raw value " + num(raw_[i]) +
                                  " is not greater than point " + std::to_string(i - 1) + "'s " +
                                  num(raw_[i - 1]) + " (raw column must be strictly increasing)");
    }
  }
  const bool increasing = si_[1] > si_[0];
  for (std::size_t i = 1; i < si_.size(); ++i) {
    const bool ok = increasing ? si_[i] > si_[i - 1] : si_[i] < si_[i - 1];
    if (!ok) {
      throw std::invalid_argument("calibration table: point " + std::to_string(i) + ": SI value " + num(si_[i]) +
                                  (si_[i] == si_[i - 1] ? " equals" : " reverses the order after") + " point " +
                                  std::to_string(i - 1) + "'s " + num(si_[i - 1]) +
                                  " (SI column must be strictly " + (increasing ? "increasing" : "decreasing") +
                                  " to be invertible)");
    }
  }
  si_increasing_ = increasing;
}

double TableCalibration::to_si(double raw) const noexcept { return interpolate(raw_, si_, raw, std::less<>{}); }

double TableCalibration::to_raw(double si) const noexcept {
  return si_increasing_ ? interpolate(si_, raw_, si, std::less<>{}) : interpolate(si_, raw_, si, std::greater<>{});
}

double Calibration::to_si(double raw) const noexcept {
  if (const auto* l = std::get_if<LinearCalibration>(&kind_)) return l->to_si(raw);
  if (const auto* t = std::get_if<TableCalibration>(&kind_)) return t->to_si(raw);
  return std::numeric_limits<double>::quiet_NaN();  // valueless: cannot happen short of a failed assignment
}

double Calibration::to_raw(double si) const noexcept {
  if (const auto* l = std::get_if<LinearCalibration>(&kind_)) return l->to_raw(si);
  if (const auto* t = std::get_if<TableCalibration>(&kind_)) return t->to_raw(si);
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace rigctl
