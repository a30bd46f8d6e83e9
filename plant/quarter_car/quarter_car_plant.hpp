// Nominal model of the quarter-car road-simulator rig of seed 000: servovalve,
// single-rod actuator with cross-port leakage, tyre plate, wheel and body on
// linear bearings with stick-slip friction. Equations and parameters are
// docs/rig-models.md 1.2 "Equations" and 1.3 "Body-bearing friction".
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "plant/quarter_car/bearing_friction.hpp"
#include "plant/quarter_car/hidden_effect_laws.hpp"
#include "plant/quarter_car/quarter_car_params.hpp"
#include "plant/simulated_plant.hpp"

namespace rigctl {

// Discrete state of the body bearing. Ignored when the friction is disabled.
enum class BearingMode : int {
  kStuck,        // body held: v_b = 0, x_b frozen, friction balances F_susp
  kSlidingUp,    // friction acts downward on the body (direction +1)
  kSlidingDown,  // friction acts upward on the body (direction -1)
};

// Full plant state in SI units. Pressures are gauge; x_w and x_b are
// deviations from static equilibrium (x_w = x_b = x_r at rest).
struct QuarterCarState {
  double x_s = 0.0;  // spool position, fraction of rated [1]
  double p1 = 0.0;   // cap-side (side 1) pressure [Pa]
  double p2 = 0.0;   // rod-side (side 2) pressure [Pa]
  double x_r = 0.0;  // actuator rod / tyre plate [m], 0 = home
  double v_r = 0.0;  // [m/s]
  double x_w = 0.0;  // wheel [m]
  double v_w = 0.0;  // [m/s]
  double x_b = 0.0;  // body [m]
  double v_b = 0.0;  // [m/s]
  BearingMode bearing = BearingMode::kStuck;
};

// The bearing's slide direction (+1 up, -1 down) and the sliding mode a
// force breaks away into.
inline int slide_direction(BearingMode m) { return m == BearingMode::kSlidingDown ? -1 : 1; }
inline BearingMode sliding_mode(double force) {
  return force >= 0.0 ? BearingMode::kSlidingUp : BearingMode::kSlidingDown;
}

// Indices into measure()'s output, in signals() order.
namespace quarter_car_signal {
inline constexpr std::size_t kXr = 0;
inline constexpr std::size_t kXw = 1;
inline constexpr std::size_t kXb = 2;
inline constexpr std::size_t kVw = 3;
inline constexpr std::size_t kVb = 4;
inline constexpr std::size_t kP1 = 5;
inline constexpr std::size_t kP2 = 6;
inline constexpr std::size_t kFt = 7;
inline constexpr std::size_t kSimVr = 8;
inline constexpr std::size_t kSimXs = 9;
inline constexpr std::size_t kSimFBearing = 10;
inline constexpr std::size_t kSimBearingStuck = 11;
inline constexpr std::size_t kCount = 12;
}  // namespace quarter_car_signal

// Body-bearing friction is a Karnopp-style hybrid stick-slip model, chosen
// because a smooth friction law evaluated at sign(v_b) inside RK4 stages
// chatters around v_b = 0 and never truly holds the body, while the rig's
// body visibly stays put until the suspension force reaches breakaway:
//  * STUCK: the body is a fixed point (dx_b/dt = dv_b/dt = 0) and the bearing
//    carries exactly the applied suspension force. At the end of each
//    sub-step, if |F_susp| > F_s (breakaway, which depends on the normal
//    force) the bearing starts sliding in the direction of F_susp.
//  * SLIDING: the friction sign is the stored slip direction, not sign(v_b),
//    so every RK4 stage of a sub-step sees one smooth vector field. When a
//    sub-step ends with v_b at or past zero, the sub-step is redone up to the
//    zero crossing (located by linear interpolation of v_b), v_b is set to 0,
//    the bearing sticks if |F_susp| <= F_s there or slides the other way
//    otherwise, and the rest of the sub-step runs in the new mode.
// Mode changes thus happen only between RK4 steps, and a stuck bearing under
// a constant force below breakaway can never toggle. Locating the crossing
// matters: rounding it to the sub-step end makes the stick-or-reverse
// decision and the lost velocity depend on the step, which moved the body by
// about 6 um between 20 and 40 sub-steps in a stick-slip run; located, the
// difference is below 0.01 um. The stick -> slip switch needs no location:
// the sliding law starts at the breakaway force, so the force on the body is
// continuous there and a late switch costs only O(h^2).
class QuarterCarPlant : public SimulatedPlant {
 public:
  explicit QuarterCarPlant(const QuarterCarParams& params);

  // x_r, x_w, x_b, v_w, v_b, p1, p2, f_t, then truth channels sim_v_r,
  // sim_x_s, sim_f_bearing, sim_bearing_stuck (see quarter_car_signal).
  // f_t is the total tyre contact load including the static F0, as the
  // contact-patch load cell reads it. sim_f_bearing is F_bearing of
  // Mb dv_b/dt = F_susp - F_bearing: positive when the rails push the body
  // down. sim_bearing_stuck is 1 while the bearing holds the body, else 0
  // (always 0 with friction disabled).
  const std::vector<ChannelInfo>& signals() const override { return signals_; }
  // {"u", "1"}: valve current as a fraction of rated, clamped to [-1, 1]
  // because the valve amplifier saturates there.
  const std::vector<ChannelInfo>& commands() const override { return commands_; }

  // Leakage-balanced rest at home (see rest_state()).
  void reset() override;
  void advance(std::span<const double> command, double dt) override;
  void measure(std::span<double> out) const override;

  // Valve offset u0 that balances the cross-port leakage at rest: with
  // leakage, P1 + P2 = Ps and P1 A1 - P2 A2 = (Mr + Mw + Mb) g, and u0 makes
  // the valve flows equal the leakage flow (about -0.043 nominally). 0
  // without leakage.
  static double rest_valve_offset(const QuarterCarParams& params);
  // Rest at x_r = 0: spool at u0, pressures as above (without leakage
  // P1 = P2 = M_T g / (A1 - A2)), all velocities 0, x_w = x_b = 0, stuck.
  static QuarterCarState rest_state(const QuarterCarParams& params);

  QuarterCarState state() const;
  // Any state, for tests and for priming a run. With the friction enabled a
  // moving body (v_b != 0) cannot be stuck: the mode is then taken as
  // sliding in the direction of v_b.
  void set_state(const QuarterCarState& s);

  // Kinetic energy + M_T g x_r (gravity and the static tyre load: both act
  // on the rod as a constant force) + tyre, suspension and end-stop springs +
  // elastic energy of the oil in both chambers, relative to 0 Pa gauge for
  // the oil now in each chamber: V (beta (exp(P/beta) - 1) - P), which is
  // -integral P dV along dP/dV = -beta/V. Conserved when nothing dissipates,
  // no oil flows and the pressures stay above cavitation.
  double total_energy() const;

  double tyre_force() const;        // F_t including F0 [N]
  double suspension_force() const;  // F_susp = ks (x_w - x_b) + bd (v_w - v_b) [N]
  double bearing_force() const;     // F_bearing [N], as sim_f_bearing
  // Bearing force levels at the current state (normal, Coulomb, breakaway).
  BearingFrictionLevels bearing_levels() const;

  const QuarterCarParams& params() const { return params_; }

  // Fault-injection hooks (drivers/sim/sim_faults.hpp): allocation-free, callable
  // between advance() calls; reset() undoes both.
  // The supply drops to p [Pa gauge]: a pump trip or a closed supply valve.
  void set_supply_pressure(double p) noexcept { supply_pressure_ = p; }
  // Chamber 1 (cap side) or 2 (rod side) opens to tank through an orifice
  // K [m^3/s/sqrt(Pa)] (outflow only: a burst pipe spills, it does not suck).
  void set_chamber_leak(int chamber, double k) noexcept {
    if (chamber == 1 || chamber == 2) chamber_leak_[static_cast<std::size_t>(chamber - 1)] = k;
  }
  // Test hook: the specimen (the suspension spring) softens during a
  // durability test (tests/procedure: the peak-valley change detector).
  // reset() does not undo it.
  void set_spring_stiffness(double k) noexcept { params_.spring_stiffness = k; }

  // The continuous model advance() integrates, for other integrators (the
  // benchmark's adaptive reference, tools/bench/reference.cpp) so that they
  // integrate these equations, not a copy: the state vector x_s, p1, p2,
  // x_r, v_r, x_w, v_w, x_b, v_b, its derivative in a given bearing mode,
  // and the pieces of the stick/slip decision. With params().hidden and the
  // fault hooks applied, as in advance().
  static constexpr std::size_t kN = 9;
  using Vec = std::array<double, kN>;
  static Vec to_vec(const QuarterCarState& s) { return {s.x_s, s.p1, s.p2, s.x_r, s.v_r, s.x_w, s.v_w, s.x_b, s.v_b}; }
  static constexpr std::size_t kVbIndex = 8;
  // The command as the plant takes it: non-finite -> 0, clamped to [-1, 1]
  // (the valve amplifier saturates there).
  static double held_command(double u) { return std::isfinite(u) ? std::clamp(u, -1.0, 1.0) : 0.0; }
  void derivatives(const Vec& y, BearingMode mode, double u, Vec& dy) const;
  void apply_floors(Vec& y) const;  // the cavitation floor of both chambers
  BearingMode mode_at_rest(const Vec& y) const;
  BearingFrictionLevels levels_at(const Vec& y) const;
  double suspension_force(const Vec& y) const;

 private:
  void rk4(Vec& y, BearingMode mode, double u, double h) const;
  void substep(double u, double h);
  void settle_mode();
  double tyre_force(const Vec& y) const;
  double seal_friction(double v_r, double p1, double p2) const;
  double effective_bulk_modulus(double p) const;
  LugreLevels lugre_levels(const Vec& y) const;
  double end_stop_force(double x_r, double v_r) const;

  QuarterCarParams params_;
  double fastest_rate_;  // [rad/s] bound for the sub-step count (quarter_car_step_size.hpp)
  std::vector<ChannelInfo> signals_;
  std::vector<ChannelInfo> commands_;
  Vec y_{};
  BearingMode mode_ = BearingMode::kStuck;
  double lugre_z_ = 0.0;  // LuGre bristle deflection [m] (QuarterCarHiddenEffects::bearing_lugre)
  double supply_pressure_ = 0.0;            // params_.supply_pressure unless a fault lowered it
  std::array<double, 2> chamber_leak_{};  // burst-pipe orifices to tank, 0 = intact
};

}  // namespace rigctl
