// Parameters of the 4-DOF half vehicle of seed paper 001, in SI. Defaults are
// the pitch-plane set of docs/rig-models.md 3.3; roll_plane() gives that
// section's roll-plane set. The paper's Table 1 mixes a full car
// (M = 2160 kg, I_y = 4140, I_x = 946 kg m^2, four unsprung masses) with the
// half-car equations; the set halves the full car and picks the springs
// and dampers inside Table 2's ranges (docs/rig-models.md 3.4.1). The
// source of each value is noted beside it.
//
// Geometry and signs (both planes, one model):
//   wheel 1 sits at lever arm l1 > 0 from the centre of gravity, wheel 2 at
//   l2 < 0: pitch l1 = +a (front), l2 = -b (rear); roll l1 = +w/2, l2 = -w/2
//   (the paper's eq. 2: Z_sr = Z_s + w/2 phi, so wheel 1 is the right wheel).
//   z_s is the body heave at the centre of gravity (up positive), phi the body
//   angle, positive when the wheel-1 end goes up (pitch: nose up). Body corner
//   i moves z_si = z_s + l_i phi (small angles). Active force F_i acts between
//   body and wheel i, positive pushing the body up and the wheel down.
//   All displacements are deviations from static equilibrium under gravity.
#pragma once

#include "plant/half_car/road_profile.hpp"

namespace rigctl {

enum class HalfCarPlane { kPitch, kRoll };

struct HalfCarParams {
  HalfCarPlane plane = HalfCarPlane::kPitch;

  // Body.
  double mass_body = 1080.0;     // m_s [kg]: half of Table 1's M = 2160 kg (docs/rig-models.md 3.4.1)
  double inertia_body = 2070.0;  // [kg m^2]: pitch, half of Table 1's I_y = 4140 (roll: I_x/2 = 473)
  double dist_front = 1.524;     // a [m], Table 1 (pitch plane)
  double dist_rear = 1.156;      // b [m], Table 1 (pitch plane)
  double track = 1.45;           // w [m], Table 1's 2W (roll plane)

  // Corners: 1 = front (pitch) or right (roll), 2 = rear or left.
  double mass_unsprung_1 = 85.0;    // [kg] Table 1 M1, M3 (front)
  double mass_unsprung_2 = 60.0;    // [kg] Table 1 M2, M4 (rear)
  double spring_1 = 80000.0;        // [N/m] Table 2 K1, K3 range 75-100 kN/m: docs/rig-models.md 3.3
  double spring_2 = 45000.0;        // [N/m] Table 2 K2, K4 range 32-70 kN/m: docs/rig-models.md 3.3
  double damper_1 = 1500.0;         // [N s/m] Table 2 C1, C3 range 875-3000: docs/rig-models.md 3.3
  double damper_2 = 1500.0;         // [N s/m] Table 2 C2, C4 range 875-3000: docs/rig-models.md 3.3
  double tyre_stiffness_1 = 200000.0;  // K_u [N/m] Table 1 Kt
  double tyre_stiffness_2 = 200000.0;  // [N/m] Table 1 Kt
  double tyre_damping_1 = 0.0;      // [N s/m] the paper's tyre is a pure spring
  double tyre_damping_2 = 0.0;      // [N s/m]

  // Optional effects (nominal off), for the diagnosis causes of
  // docs/run-files.md 2.5. The linear model of eq. 5 ignores them.
  double damper_rebound_factor = 1.0;  // rebound (extension) damping / compression damping; 1 = linear damper
  // [m/s] knee of a digressive damper (the second form of asymmetry): above
  // it the rebound force grows at a third of its low-speed rate; 0 = linear.
  double damper_rebound_knee = 0.0;
  double actuator_time_constant = 0.0; // [s] first-order lag of the active force behind its command; 0 = ideal
  // [s] a second, faster lag ahead of the first (the servo-valve spool
  // feeding the force loop): with it the actuator is second order, force
  // following command through 1/((tau1 s + 1)(tau2 s + 1)), whose mean delay
  // is tau1 + tau2. Needs actuator_time_constant > 0; 0 = none.
  double actuator_valve_time_constant = 0.0;
  double actuator_force_limit = 0.0;   // [N] actuator saturation in the plant; 0 = none (controllers clamp)

  // Vehicle speed: sets the bump's timing, the rear delay (a + b)/V of
  // eq. 11 and the centrifugal force of eq. 6.
  double speed = 20.0;  // V [m/s], paper

  // Curve (roll plane only, eqs. 6-8): M_roll = m_s V^2 / R h_roll acting on
  // the body. Positive R puts the curve centre on wheel 1's side, so the
  // body rolls outwards with phi > 0. The force acts on the sprung mass at
  // its centre of gravity (h_roll is the distance from the roll centre to
  // that centre of gravity, eq. 7); the unsprung masses' share goes straight
  // to the ground. The gravity moment m_s g h_roll phi of the rolled body
  // is not in the paper's eq. 8 and is left out.
  double curve_radius = 0.0;      // R [m]; 0 = straight road
  double roll_arm = 0.5;          // h_roll [m], docs/rig-models.md 3.3 ("roll-centre height")
  double curve_start_time = 0.0;  // [s] entry into the curve
  double curve_ramp_time = 0.0;   // [s] lateral acceleration ramps in linearly (a clothoid); 0 = step

  double gravity = 9.81;  // g [m/s^2]

  RoadProfileSpec road;

  // RK4 sub-steps per control period. 10 at 2.5 ms gives 0.25 ms: 40 steps
  // per period of the paper's 100 Hz bump and far inside the stability
  // limit of the ~10 Hz wheel hop.
  int substeps = 10;

  // docs/rig-models.md 3.3 roll plane: body 1080 kg, roll inertia 473 kg m^2
  // (Table 1's I_x = 946 halved), track 1.45 m, 85 kg unsprung each side,
  // 80 kN/m springs, 1500 N s/m dampers, roll arm 0.5 m, 200 kN/m tyres;
  // curve radius 100 m (chosen: 4 m/s^2 lateral at 20 m/s, a brisk ordinary
  // curve; the paper gives none), entered at 0.5 s.
  static HalfCarParams roll_plane();
};

// Lever arm l_i [m] of wheel i (0 or 1) from the centre of gravity.
double half_car_lever_arm(const HalfCarParams& p, int wheel);
// Centrifugal roll moment m_s V^2 / R h_roll [N m] once fully in the curve
// (0 on a straight road or in the pitch plane).
double half_car_roll_moment(const HalfCarParams& p);
// Static tyre load of wheel i [N]: its unsprung weight plus the body
// weight shared by the lever arms (l_other / (l_other - l_i)).
double half_car_static_tyre_load(const HalfCarParams& p, int wheel);
// Throws std::invalid_argument naming the first bad value.
void validate(const HalfCarParams& p);

}  // namespace rigctl
