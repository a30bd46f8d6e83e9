#include "plant/half_car/half_car_params.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rigctl {

HalfCarParams HalfCarParams::roll_plane() {
  HalfCarParams p;
  p.plane = HalfCarPlane::kRoll;
  p.mass_body = 1080.0;
  p.inertia_body = 473.0;  // Table 1's I_x = 946 kg m^2 halved
  p.track = 1.45;
  p.mass_unsprung_1 = p.mass_unsprung_2 = 85.0;
  p.spring_1 = p.spring_2 = 80000.0;
  p.damper_1 = p.damper_2 = 1500.0;
  p.tyre_stiffness_1 = p.tyre_stiffness_2 = 200000.0;
  p.roll_arm = 0.5;
  p.curve_radius = 100.0;
  p.curve_start_time = 0.5;
  p.road.kind = RoadKind::kFlat;
  return p;
}

double half_car_lever_arm(const HalfCarParams& p, int wheel) {
  if (p.plane == HalfCarPlane::kPitch) return wheel == 0 ? p.dist_front : -p.dist_rear;
  return wheel == 0 ? 0.5 * p.track : -0.5 * p.track;
}

double half_car_roll_moment(const HalfCarParams& p) {
  if (p.plane != HalfCarPlane::kRoll || p.curve_radius == 0.0) return 0.0;
  return p.mass_body * p.speed * p.speed / p.curve_radius * p.roll_arm;
}

double half_car_static_tyre_load(const HalfCarParams& p, int wheel) {
  const double li = half_car_lever_arm(p, wheel);
  const double lo = half_car_lever_arm(p, 1 - wheel);
  const double body_share = lo / (lo - li);
  const double mu = wheel == 0 ? p.mass_unsprung_1 : p.mass_unsprung_2;
  return (p.mass_body * body_share + mu) * p.gravity;
}

void validate(const HalfCarParams& p) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(std::string("half car: ") + name + " must be positive");
  };
  auto non_negative = [](double v, const char* name) {
    if (!(v >= 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("half car: ") + name + " must not be negative");
    }
  };
  positive(p.mass_body, "mass_body");
  positive(p.inertia_body, "inertia_body");
  if (p.plane == HalfCarPlane::kPitch) {
    positive(p.dist_front, "dist_front");
    positive(p.dist_rear, "dist_rear");
  } else {
    positive(p.track, "track");
  }
  positive(p.mass_unsprung_1, "mass_unsprung_1");
  positive(p.mass_unsprung_2, "mass_unsprung_2");
  non_negative(p.spring_1, "spring_1");
  non_negative(p.spring_2, "spring_2");
  non_negative(p.damper_1, "damper_1");
  non_negative(p.damper_2, "damper_2");
  positive(p.tyre_stiffness_1, "tyre_stiffness_1");
  positive(p.tyre_stiffness_2, "tyre_stiffness_2");
  non_negative(p.tyre_damping_1, "tyre_damping_1");
  non_negative(p.tyre_damping_2, "tyre_damping_2");
  positive(p.damper_rebound_factor, "damper_rebound_factor");
  non_negative(p.actuator_time_constant, "actuator_time_constant");
  non_negative(p.actuator_valve_time_constant, "actuator_valve_time_constant");
  if (p.actuator_valve_time_constant > 0.0 && !(p.actuator_time_constant > 0.0)) {
    throw std::invalid_argument("half car: actuator_valve_time_constant needs actuator_time_constant > 0");
  }
  non_negative(p.actuator_force_limit, "actuator_force_limit");
  positive(p.speed, "speed");
  if (!std::isfinite(p.curve_radius)) throw std::invalid_argument("half car: curve_radius must be finite");
  non_negative(p.roll_arm, "roll_arm");
  non_negative(p.curve_start_time, "curve_start_time");
  non_negative(p.curve_ramp_time, "curve_ramp_time");
  non_negative(p.gravity, "gravity");
  if (p.substeps < 1) throw std::invalid_argument("half car: substeps must be at least 1");
}

}  // namespace rigctl
