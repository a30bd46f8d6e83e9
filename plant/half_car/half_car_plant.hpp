// Simulator of the 4-DOF half vehicle of seed 001 on a two-post rig: body
// heave and angle (pitch or roll), two unsprung masses, spring, damper and
// tyre per corner, active forces F1, F2 between body and wheels, the road
// (owned by the plant, advanced with its time) under the tyres and, in the
// roll plane, the centrifugal roll moment of eqs. 6-8. Equations: eqs. 1-4 in
// the centre-of-gravity coordinates of half_car_model.hpp, with:
//  * Gravity: displacements are deviations from static equilibrium. Springs
//    and tyres carry their static loads at zero deflection, so gravity
//    cancels while the tyres touch. Tyre i's static load F0_i (its unsprung
//    weight plus the lever-arm share of the body weight) is kept, and the
//    total tyre force is F0_i + kt_i (z_ri - z_ui) + ct_i (z_ri' - z_ui').
//  * Lift-off: a tyre cannot pull. Its compression from the free radius is
//    F0_i/kt_i + z_ri - z_ui; at or below zero the tyre force is 0 and the
//    contact flag drops, so the wheel then falls under its own weight and the
//    suspension force. The total force is also floored at 0 while in contact
//    (tyre damping cannot pull either).
//  * Optional effects (nominal off): rebound damping differing from
//    compression (piecewise linear: a sharp switch at zero rate), a first-
//    or second-order lag of the actuator force (a valve stage ahead of the
//    force loop), actuator saturation. The lags are states of the RK4, so
//    they act within a control period, not per sample.
// Fixed-step RK4 with `substeps` steps per advance(); road and roll moment are
// evaluated at each stage's time. No allocation in advance() or measure().
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "plant/half_car/half_car_params.hpp"
#include "plant/half_car/road_profile.hpp"
#include "plant/simulated_plant.hpp"

namespace rigctl {

struct HalfCarState {
  double z_s = 0.0;    // body heave at the centre of gravity [m]
  double phi = 0.0;    // body angle [rad]
  double z_u1 = 0.0;   // wheel 1 [m]
  double z_u2 = 0.0;   // wheel 2 [m]
  double v_s = 0.0;    // [m/s]
  double omega = 0.0;  // dphi/dt [rad/s]
  double v_u1 = 0.0;   // [m/s]
  double v_u2 = 0.0;   // [m/s]
  double f_act1 = 0.0; // actuator forces acting now [N] (lag state)
  double f_act2 = 0.0;
  double time = 0.0;   // plant time since reset [s]: positions the road and the curve
  double f_valve1 = 0.0;  // valve-stage forces [N] (second lag state; used with actuator_valve_time_constant)
  double f_valve2 = 0.0;
};

// Indices into measure()'s output, in signals() order.
namespace half_car_signal {
inline constexpr std::size_t kZr1 = 0;      // road under wheel 1 [m]
inline constexpr std::size_t kZr2 = 1;      // road under wheel 2 [m]
inline constexpr std::size_t kZs = 2;       // body heave at the centre of gravity [m]
inline constexpr std::size_t kPhi = 3;      // body pitch (or roll) angle [rad]
inline constexpr std::size_t kZu1 = 4;      // wheel 1 [m]
inline constexpr std::size_t kZu2 = 5;      // wheel 2 [m]
inline constexpr std::size_t kZsDot = 6;    // body heave velocity [m/s]
inline constexpr std::size_t kZsDdot = 7;   // body heave acceleration [m/s^2] (accelerometer at the CG)
inline constexpr std::size_t kPhiDot = 8;   // angle rate [rad/s] (gyro)
inline constexpr std::size_t kPhiDdot = 9;  // angular acceleration [rad/s^2]
inline constexpr std::size_t kZu1Dot = 10;  // wheel 1 velocity [m/s]
inline constexpr std::size_t kZu2Dot = 11;  // wheel 2 velocity [m/s]
inline constexpr std::size_t kTravel1 = 12; // suspension travel z_s + l1 phi - z_u1 [m], + = extended
inline constexpr std::size_t kTravel2 = 13;
inline constexpr std::size_t kSimTyreForce1 = 14;  // total tyre load incl. static [N], >= 0
inline constexpr std::size_t kSimTyreForce2 = 15;
inline constexpr std::size_t kSimContact1 = 16;    // 1 in contact, 0 lifted off
inline constexpr std::size_t kSimContact2 = 17;
inline constexpr std::size_t kSimFAct1 = 18;       // actuator force acting [N]
inline constexpr std::size_t kSimFAct2 = 19;
inline constexpr std::size_t kSimMRoll = 20;       // centrifugal roll moment [N m]
inline constexpr std::size_t kCount = 21;
}  // namespace half_car_signal

class HalfCarPlant : public SimulatedPlant {
 public:
  explicit HalfCarPlant(const HalfCarParams& params);

  // z_r1, z_r2, z_s, phi, z_u1, z_u2 (run-file names), then z_s_dot,
  // z_s_ddot, phi_dot, phi_ddot, z_u1_dot, z_u2_dot, susp_travel_1,
  // susp_travel_2, and the truth channels sim_tyre_force_1/2,
  // sim_contact_1/2, sim_f_act_1/2, sim_m_roll (see half_car_signal).
  // The accelerations are those at the sample instant under the command
  // held over the period that just ended.
  const std::vector<ChannelInfo>& signals() const override { return signals_; }
  // {"f_1", "N"}, {"f_2", "N"}: active forces (0 = passive). Non-finite
  // commands act as 0; clamped to actuator_force_limit when that is set.
  const std::vector<ChannelInfo>& commands() const override { return commands_; }

  // Static equilibrium at time 0, actuators idle.
  void reset() override;
  void advance(std::span<const double> command, double dt) override;
  void measure(std::span<double> out) const override;

  HalfCarState state() const;
  void set_state(const HalfCarState& s);

  double tyre_force(int wheel) const;  // total, incl. static load [N]
  bool in_contact(int wheel) const;
  double static_tyre_load(int wheel) const { return static_load_[static_cast<std::size_t>(wheel)]; }
  double lever_arm(int wheel) const { return lever_[static_cast<std::size_t>(wheel)]; }
  double roll_moment(double t) const;  // M_roll at time t [N m]
  const RoadProfile& road() const { return road_; }
  const HalfCarParams& params() const { return params_; }

  // The continuous model advance() integrates, for other integrators (the
  // benchmark's adaptive reference, tools/bench/reference.cpp) so that they
  // integrate these equations, not a copy: the state vector z_s, phi, z_u1,
  // z_u2, v_s, omega, v_u1, v_u2, f_act1, f_act2, f_valve1, f_valve2 and its
  // derivative at time t (road, roll moment) under held command u.
  static constexpr std::size_t kN = 12;
  using Vec = std::array<double, kN>;
  using Command2 = std::array<double, 2>;
  static Vec to_vec(const HalfCarState& s) {
    return {s.z_s, s.phi, s.z_u1, s.z_u2, s.v_s, s.omega, s.v_u1, s.v_u2, s.f_act1, s.f_act2, s.f_valve1, s.f_valve2};
  }
  // The command as the plant takes it (non-finite -> 0, the force limit).
  Command2 held_command(std::span<const double> command) const;
  // What holding u does to the state at once: an ideal actuator (no lag) is
  // the command, a missing valve stage passes it.
  void hold_command(const Command2& u, Vec& y) const;
  double damper_force(double c, double rate) const;  // [N] of a corner's damper at suspension rate
  void derivatives(const Vec& y, double t, const Command2& u, Vec& dy) const;

 private:
  void rk4(double h);
  double tyre_force_at(const Vec& y, int wheel, double t) const;

  HalfCarParams params_;
  RoadProfile road_;
  std::vector<ChannelInfo> signals_;
  std::vector<ChannelInfo> commands_;
  std::array<double, 2> lever_{};
  std::array<double, 2> static_load_{};
  std::array<double, 2> free_compression_{};  // F0_i / kt_i [m]
  double roll_moment_full_ = 0.0;
  Vec y_{};
  double t_ = 0.0;
  Command2 u_{};  // command held over the current period
};

}  // namespace rigctl
