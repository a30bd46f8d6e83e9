// The `plant:` section of the half car (seed 001): body, two corners, speed,
// curve, optional effects and the road. SI throughout (the key names carry
// the unit); every key is required, whichever plane or road kind is chosen,
// so that a case switching plane or road finds everything it needs.
#include <cmath>
#include <limits>
#include <stdexcept>

#include "config/plant_readers.hpp"

namespace rigctl {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void read_corner(ConfigReader r, double& unsprung, double& spring, double& damper, double& tyre_k, double& tyre_c) {
  unsprung = r.number("unsprung_mass_kg", 1e-3, 1e5);
  spring = r.number("spring_n_per_m", 0.0, 1e9);
  damper = r.number("damper_n_s_per_m", 0.0, 1e9);
  tyre_k = r.number("tyre_stiffness_n_per_m", 1.0, 1e10);
  tyre_c = r.number("tyre_damping_n_s_per_m", 0.0, 1e9);
  r.reject_unknown_keys();
}

IsoRoadClass iso_class(const std::string& c) {
  if (c == "A") return IsoRoadClass::kA;
  if (c == "B") return IsoRoadClass::kB;
  if (c == "C") return IsoRoadClass::kC;
  if (c == "D") return IsoRoadClass::kD;
  return IsoRoadClass::kE;
}

void read_road(ConfigReader r, RoadProfileSpec& road) {
  const std::string kind = r.choice("kind", {"flat", "bump", "iso8608"});
  road.kind = kind == "flat" ? RoadKind::kFlat : kind == "bump" ? RoadKind::kBump : RoadKind::kIso8608;
  const std::string wheels = r.choice("wheels", {"both", "wheel_1", "wheel_2"});
  road.wheels = wheels == "both" ? RoadWheels::kBoth : wheels == "wheel_1" ? RoadWheels::kWheel1 : RoadWheels::kWheel2;

  auto b = r.child("bump");  // eqs. 9-10
  road.bump.amplitude = b.number("amplitude_m", 0.0, 1.0);
  road.bump.wavelength = b.number("wavelength_m", 1e-4, 1e3);
  road.bump.start_time = b.number("start_time_s", 0.0, 1e5);
  road.bump.cycles = b.number("cycles", 1e-3, 1e4);
  b.reject_unknown_keys();

  auto iso = r.child("iso8608");
  road.iso.road_class = iso_class(iso.choice("class", {"A", "B", "C", "D", "E"}));
  road.iso.gd_n0 = iso.number("gd_n0_m3", 0.0, 1.0);
  road.iso.seed = static_cast<uint64_t>(iso.integer("seed", 0, std::numeric_limits<int64_t>::max()));
  road.iso.n_min = iso.number("n_min_cycles_per_m", 1e-4, 100.0);
  road.iso.n_max = iso.number("n_max_cycles_per_m", 1e-4, 100.0);
  if (!(road.iso.n_max > road.iso.n_min)) iso.fail("n_max_cycles_per_m", "must be above n_min_cycles_per_m");
  road.iso.length = iso.number("length_m", 100.0, 1e6);
  if (road.iso.length * road.iso.n_min < 1.0) {
    iso.fail("length_m", "must hold the longest wave: at least 1 / n_min_cycles_per_m = " +
                              std::to_string(1.0 / road.iso.n_min) + " m");
  }
  // The road is generated on a grid of 8 points per shortest wave (plant/half_car/iso_road_table.hpp).
  if (road.iso.length * 8.0 * road.iso.n_max > 16.0e6) {
    iso.fail("length_m", "times 8 n_max_cycles_per_m would need over 16 million grid points; shorten it or lower n_max");
  }
  road.iso.fade_in_distance = iso.number("fade_in_distance_m", 0.0, 1e5);
  iso.reject_unknown_keys();

  auto tr = r.child("bump_train");  // humps on top of the kind above (diagnosis runs)
  road.train.amplitude = tr.number("amplitude_m", -1.0, 1.0);
  road.train.wavelength = tr.number("wavelength_m", 1e-3, 1e3);
  road.train.start_time = tr.number("start_time_s", 0.0, 1e5);
  road.train.interval = tr.number("interval_s", 1e-3, 1e5);
  road.train.count = static_cast<int>(tr.integer("count", 0, 100000));
  tr.reject_unknown_keys();
  r.reject_unknown_keys();
}

}  // namespace

void read_half_car_plant(ConfigReader r, HalfCarParams& p) {
  p.plane = r.choice("plane", {"pitch", "roll"}) == "pitch" ? HalfCarPlane::kPitch : HalfCarPlane::kRoll;
  p.substeps = static_cast<int>(r.integer("substeps", 1, 10000));

  auto body = r.child("body");
  p.mass_body = body.number("mass_kg", 1e-3, 1e6);
  p.inertia_body = body.number("inertia_kg_m2", 1e-3, 1e7);
  p.dist_front = body.number("dist_front_m", 1e-3, 100.0);
  p.dist_rear = body.number("dist_rear_m", 1e-3, 100.0);
  p.track = body.number("track_m", 1e-3, 100.0);
  body.reject_unknown_keys();

  read_corner(r.child("corner_1"), p.mass_unsprung_1, p.spring_1, p.damper_1, p.tyre_stiffness_1, p.tyre_damping_1);
  read_corner(r.child("corner_2"), p.mass_unsprung_2, p.spring_2, p.damper_2, p.tyre_stiffness_2, p.tyre_damping_2);

  p.speed = r.number("vehicle_speed_m_s", 1e-3, 200.0);

  auto curve = r.child("curve");  // eqs. 6-8, roll plane only
  p.curve_radius = curve.number("radius_m", -1e7, 1e7);
  if (p.curve_radius != 0.0 && std::abs(p.curve_radius) < 1.0) curve.fail("radius_m", "must be 0 (straight) or at least 1 m");
  p.roll_arm = curve.number("roll_arm_m", 0.0, 10.0);
  p.curve_start_time = curve.number("start_time_s", 0.0, 1e5);
  p.curve_ramp_time = curve.number("ramp_time_s", 0.0, 1e5);
  curve.reject_unknown_keys();

  auto fx = r.child("effects");
  p.damper_rebound_factor = fx.number("damper_rebound_factor", 1e-3, 1e3);
  p.actuator_time_constant = fx.number("actuator_time_constant_s", 0.0, 10.0);
  p.actuator_valve_time_constant = fx.number("actuator_valve_time_constant_s", 0.0, 10.0);
  p.actuator_force_limit = fx.number("actuator_force_limit_n", 0.0, kInf);
  fx.reject_unknown_keys();

  p.gravity = r.number("gravity_m_s2", 0.0, 100.0);
  read_road(r.child("road"), p.road);
  if (const auto& tr = p.road.train; tr.count > 0 && tr.amplitude != 0.0 && tr.interval < tr.wavelength / p.speed) {
    r.child("road").child("bump_train").fail("interval_s", "must be at least one hump's duration (wavelength / speed)");
  }
  try {
    validate(p);
  } catch (const std::invalid_argument& e) {
    r.fail("plane", e.what());
  }
  r.reject_unknown_keys();
}

}  // namespace rigctl
