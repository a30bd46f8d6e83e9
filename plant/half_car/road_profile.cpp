#include "plant/half_car/road_profile.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kN0 = 0.1;  // ISO 8608 reference spatial frequency [cycle/m]

}  // namespace

double iso8608_gd_n0(IsoRoadClass c) {
  switch (c) {
    case IsoRoadClass::kA: return 16e-6;
    case IsoRoadClass::kB: return 64e-6;
    case IsoRoadClass::kC: return 256e-6;
    case IsoRoadClass::kD: return 1024e-6;
    case IsoRoadClass::kE: return 4096e-6;
  }
  return 0.0;
}

RoadProfile::RoadProfile(const RoadProfileSpec& spec, double speed, WheelArrangement arrangement, double wheelbase)
    : spec_(spec), speed_(speed), arrangement_(arrangement), wheelbase_(wheelbase) {
  if (!(speed > 0.0) || !std::isfinite(speed)) throw std::invalid_argument("road: speed must be positive");
  if (arrangement == WheelArrangement::kInLine && !(wheelbase >= 0.0)) {
    throw std::invalid_argument("road: wheelbase must not be negative");
  }
  if (spec.kind == RoadKind::kBump) {
    if (!(spec.bump.wavelength > 0.0)) throw std::invalid_argument("road: bump wavelength must be positive");
    if (!(spec.bump.cycles > 0.0)) throw std::invalid_argument("road: bump cycles must be positive");
    if (!std::isfinite(spec.bump.amplitude)) throw std::invalid_argument("road: bump amplitude must be finite");
  }
  {
    const auto& b = spec.train;
    if (!std::isfinite(b.amplitude)) throw std::invalid_argument("road: bump train amplitude must be finite");
    if (b.count < 0) throw std::invalid_argument("road: bump train count must not be negative");
    if (b.count > 0 && b.amplitude != 0.0) {
      if (!(b.wavelength > 0.0)) throw std::invalid_argument("road: bump train wavelength must be positive");
      if (!(b.start_time >= 0.0)) throw std::invalid_argument("road: bump train start time must not be negative");
      if (!(b.interval >= b.wavelength / speed)) {
        throw std::invalid_argument("road: bump train interval must be at least one hump's duration (wavelength / speed)");
      }
    }
  }
  if (spec.kind == RoadKind::kIso8608) {
    const auto& iso = spec.iso;
    if (!(iso.n_min > 0.0) || !(iso.n_max > iso.n_min)) {
      throw std::invalid_argument("road: ISO band needs 0 < n_min < n_max");
    }
    if (iso.gd_n0 < 0.0) throw std::invalid_argument("road: Gd(n0) must not be negative");
    if (iso.fade_in_distance < 0.0) throw std::invalid_argument("road: fade-in distance must not be negative");
    gd_n0_ = iso.gd_n0 > 0.0 ? iso.gd_n0 : iso8608_gd_n0(iso.road_class);
    IsoRoadTableSpec table;
    table.gd_n0 = gd_n0_;
    table.n_min = iso.n_min;
    table.n_max = iso.n_max;
    table.seed = iso.seed;
    table.tracks = 2;
    table.min_length = iso.length;
    iso_table_ = std::make_shared<const IsoRoadTable>(table);
  }
}

double RoadProfile::iso_variance() const noexcept {
  if (spec_.kind != RoadKind::kIso8608) return 0.0;
  return gd_n0_ * kN0 * kN0 * (1.0 / spec_.iso.n_min - 1.0 / spec_.iso.n_max);
}

double RoadProfile::delay(int wheel) const noexcept {
  if (wheel == 1 && arrangement_ == WheelArrangement::kInLine) return wheelbase_ / speed_;
  return 0.0;
}

RoadSample RoadProfile::bump(double tau) const noexcept {
  const auto& b = spec_.bump;
  const double duration = b.cycles * b.wavelength / speed_;
  if (tau < 0.0 || tau > duration) return {};
  const double w = kTwoPi * speed_ / b.wavelength;
  return {0.5 * b.amplitude * (1.0 - std::cos(w * tau)), 0.5 * b.amplitude * w * std::sin(w * tau)};
}

RoadSample RoadProfile::train(double t_wheel) const noexcept {
  const auto& b = spec_.train;
  if (b.count <= 0 || b.amplitude == 0.0) return {};
  const double since = t_wheel - b.start_time;
  if (since < 0.0) return {};
  const double k = std::floor(since / b.interval);
  if (k >= static_cast<double>(b.count)) return {};
  const double tau = since - k * b.interval;
  if (tau > b.wavelength / speed_) return {};
  const double w = kTwoPi * speed_ / b.wavelength;
  return {0.5 * b.amplitude * (1.0 - std::cos(w * tau)), 0.5 * b.amplitude * w * std::sin(w * tau)};
}

double RoadProfile::track_height(int track, double x) const noexcept {
  return iso_table_ ? iso_table_->at(track, x).z : 0.0;
}

// Height and slope dz/dx of a track with the fade-in applied.
RoadSample RoadProfile::iso(int track, double x) const noexcept {
  if (x <= 0.0) return {};
  const IsoRoadTable::Point p = iso_table_->at(track, x);
  double z = p.z, slope = p.slope;
  const double fade = spec_.iso.fade_in_distance;
  if (fade > 0.0 && x < fade) {
    const double g = 0.5 * (1.0 - std::cos(std::numbers::pi * x / fade));
    const double dg = 0.5 * std::numbers::pi / fade * std::sin(std::numbers::pi * x / fade);
    slope = g * slope + dg * z;
    z *= g;
  }
  return {z, slope};
}

RoadSample RoadProfile::at(int wheel, double t) const noexcept {
  if (spec_.wheels == RoadWheels::kWheel1 && wheel != 0) return {};
  if (spec_.wheels == RoadWheels::kWheel2 && wheel != 1) return {};
  const double t_wheel = t - delay(wheel);
  RoadSample base;
  switch (spec_.kind) {
    case RoadKind::kFlat: break;
    case RoadKind::kBump: base = bump(t_wheel - spec_.bump.start_time); break;
    case RoadKind::kIso8608: {
      const int track = arrangement_ == WheelArrangement::kSideBySide ? wheel : 0;
      const RoadSample s = iso(track, speed_ * t_wheel);
      base = {s.z, s.dz * speed_};
      break;
    }
  }
  const RoadSample extra = train(t_wheel);
  return {base.z + extra.z, base.dz + extra.dz};
}

}  // namespace rigctl
