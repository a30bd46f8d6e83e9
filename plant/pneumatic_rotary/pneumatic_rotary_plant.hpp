// Nominal model of the flexible-bladder rotary pneumatic servo of seed 002:
// solenoid spool valve with dither, Shearer-linearised valve flows and
// chambers in the time domain, inertial load with bladder hysteresis, Coulomb
// brake and end stops. Equations and parameters: docs/rig-models.md
// section 2 (2.2 "Equations", 2.5 "Parameters").
//
//   U_v = u + valve_null_offset + A_d sin(2 pi f_d t)       (dither if enabled)
//   x   = sat(k_sol U_v, +-spool_limit)
//   x_o = sign(x) max(|x| - overlap, 0)                      (spool overlap, 0 nominal)
//   m_a =  C1 x_o - C2 p_a,  m_b = -C1 x_o - C2 p_b          (p: change from Pq)
//   dp_a/dt = (gamma R T / V) m_a - gamma Pq alpha omega / V
//   dp_b/dt = (gamma R T / V) m_b + gamma Pq alpha omega / V
//   I domega/dt = alpha (p_a - p_b) + T_stop - T_hysteresis - T_friction
// Signs: +u opens the valve into bladder a, whose volume V + alpha theta grows
// with theta, so +u drives theta up and alpha (p_a - p_b) does work
// alpha dp omega that the chambers lose (see stored_energy()).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "plant/pneumatic_rotary/bladder_hysteresis.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_params.hpp"
#include "plant/simulated_plant.hpp"

namespace rigctl {

// Discrete state of the load. Only acted on when the bladder hysteresis or
// the brake is enabled; without either the load moves freely and the mode
// merely reports the sign of omega.
enum class RotaryLoadMode : int {
  kStuck,            // omega = 0, theta frozen; the friction-like parts carry the residual torque
  kSlidingPositive,  // moving towards +theta: step part and brake act at -h_s - T_c
  kSlidingNegative,
};

// Full plant state in SI units.
struct PneumaticRotaryState {
  double theta = 0.0;  // output angle from mid-stroke [rad]
  double omega = 0.0;  // [rad/s]
  double p_a = 0.0;    // bladder a pressure, change from Pq [Pa]
  double p_b = 0.0;    // bladder b pressure, change from Pq [Pa]
  double time = 0.0;   // plant time since reset [s]: sets the dither phase
  RotaryLoadMode mode = RotaryLoadMode::kStuck;
  HysteresisAnchor anchor;  // memory of the hysteresis ramp (bladder_hysteresis.hpp)
};

// A sliding mode's direction (+1, -1; 0 when stuck) and the mode for one.
inline int slide_direction(RotaryLoadMode m) {
  return m == RotaryLoadMode::kSlidingPositive ? 1 : (m == RotaryLoadMode::kSlidingNegative ? -1 : 0);
}
inline RotaryLoadMode mode_for(int direction) {
  return direction > 0 ? RotaryLoadMode::kSlidingPositive
                       : (direction < 0 ? RotaryLoadMode::kSlidingNegative : RotaryLoadMode::kStuck);
}

// Indices into measure()'s output, in signals() order.
namespace pneumatic_rotary_signal {
inline constexpr std::size_t kTheta = 0;
inline constexpr std::size_t kDp = 1;
inline constexpr std::size_t kOmega = 2;
inline constexpr std::size_t kSimPa = 3;
inline constexpr std::size_t kSimPb = 4;
inline constexpr std::size_t kSimX = 5;
inline constexpr std::size_t kSimTHysteresis = 6;
inline constexpr std::size_t kSimTFriction = 7;
inline constexpr std::size_t kCount = 8;
}  // namespace pneumatic_rotary_signal

// Hysteresis step part and brake form one hybrid stick/slip element, as the
// quarter-car bearing does (and for the same reason: a sign(omega) law inside
// RK4 stages chatters at rest and never truly holds the load):
//  * STUCK: theta frozen, omega = 0; the pressures still evolve. The residual
//    R = alpha dp + T_stop - T_elastic(theta) is carried by the step part and
//    the brake, shared in proportion to their levels h_s and T_c. At the end
//    of each sub-step, |R| > h_s + T_c starts sliding in the direction of R;
//    the torque on the load is continuous there (pure Coulomb starts at its
//    level), so a late switch costs O(h^2).
//  * SLIDING: step part and brake are (h_s + T_c) times the stored direction.
//    When a sub-step ends with omega at or past zero, the sub-step is redone
//    up to the crossing (linear interpolation of omega), omega is set to 0,
//    the load sticks if |R| <= h_s + T_c there or reverses otherwise, and the
//    rest of the sub-step runs in the new mode. Every mode change re-anchors
//    the hysteresis ramp, so a reversal is exactly where the ramp restarts.
// With the valve dithering, the 50 Hz pressure ripple (+-540 Pa per bladder,
// +-0.13 N m) is well inside the holding band of the nominal +-2 % hysteresis
// (0.75 N m), so a held load stays held rather than creeping.
class PneumaticRotaryPlant : public SimulatedPlant {
 public:
  explicit PneumaticRotaryPlant(const PneumaticRotaryParams& params);

  // theta [rad], dp [Pa] = p_a - p_b, omega [rad/s], then the truth channels
  // sim_pa, sim_pb [Pa] (changes from Pq), sim_x [m] (spool, with dither),
  // sim_t_hysteresis [N m], sim_t_friction [N m] (brake). The two torques are
  // signed as they oppose the load: positive when they push towards -theta.
  const std::vector<ChannelInfo>& signals() const override { return signals_; }
  // {"u", "V"}: controller output voltage as the DAC puts it out.
  const std::vector<ChannelInfo>& commands() const override { return commands_; }

  // At rest at theta = 0, p_a = p_b = 0, time 0 (dither phase 0), hysteresis
  // unloaded, stuck.
  void reset() override;
  void advance(std::span<const double> command, double dt) override;
  void measure(std::span<double> out) const override;

  PneumaticRotaryState state() const;
  // Any state, for tests and for priming a run. With stick/slip active a
  // moving load (omega != 0) cannot be stuck: the mode is then taken as
  // sliding in the direction of omega.
  void set_state(const PneumaticRotaryState& s);

  // Spool position [m] for command u [V] at plant time t [s].
  double spool_position(double u, double t) const;
  // Port opening [m] at spool position x: x less the overlap, 0 inside it.
  double port_opening(double x) const;

  double hysteresis_torque() const;  // as sim_t_hysteresis [N m]
  double friction_torque() const;    // as sim_t_friction [N m]

  // Kinetic energy + end-stop spring + energy stored in the hysteresis ramp
  // (T_elastic^2 / 2 k_h) + the chambers' quadratic form V (p_a^2 + p_b^2) /
  // (2 gamma Pq). The last term is what the linearised chamber equations
  // conserve: its rate is -alpha dp omega + (R T / Pq)(p_a m_a + p_b m_b).
  // Constant with the valve closed (no dither), C2 = 0 and no hysteresis,
  // brake or end-stop damping.
  double stored_energy() const;

  const BladderHysteresisLevels& hysteresis_levels() const { return hysteresis_; }
  double brake_level() const { return brake_; }  // T_c [N m]
  const PneumaticRotaryParams& params() const { return params_; }

  // The continuous model advance() integrates, for other integrators (the
  // benchmark's adaptive reference, tools/bench/reference.cpp) so that they
  // integrate these equations, not a copy: the state vector theta, omega,
  // p_a, p_b, its derivative in a given mode under the present hysteresis
  // anchor, and the pieces of the stick/slip decision.
  static constexpr std::size_t kN = 4;
  using Vec = std::array<double, kN>;
  static constexpr std::size_t kOmegaIndex = 1;
  static double held_command(double u) { return std::isfinite(u) ? u : 0.0; }
  void derivatives(const Vec& y, double t, RotaryLoadMode mode, double u, Vec& dy) const;
  double residual_torque(const Vec& y) const;  // load torque the holding band must resist
  RotaryLoadMode mode_at_rest(const Vec& y) const;
  // Enters `mode` at angle theta: the hysteresis ramp is re-anchored there.
  void enter_mode_at(RotaryLoadMode mode, double theta);
  bool stick_slip() const { return stick_slip_; }
  double holding_torque() const { return holding_; }  // h_s + T_c [N m]

 private:
  void rk4(Vec& y, double t, RotaryLoadMode mode, double u, double h) const;
  void substep(double u, double h);
  double end_stop_torque(double theta, double omega) const;
  double elastic_torque(double theta) const;
  void enter_mode(RotaryLoadMode mode);

  PneumaticRotaryParams params_;
  std::vector<ChannelInfo> signals_;
  std::vector<ChannelInfo> commands_;
  BladderHysteresisLevels hysteresis_;
  double brake_ = 0.0;
  double holding_ = 0.0;      // h_s + T_c [N m]
  bool stick_slip_ = false;   // hysteresis or brake enabled
  double gas_gain_ = 0.0;     // gamma R T / V [Pa/kg]
  double motion_gain_ = 0.0;  // gamma Pq alpha / V [Pa/rad]

  Vec y_{};
  double t_ = 0.0;
  double u_ = 0.0;  // last command, for measure()'s spool
  double bouc_wen_z_ = 0.0;  // PneumaticHiddenForms: Bouc-Wen hysteresis state [-1, 1]
  double hidden_torque(double omega) const;  // the second forms' hysteresis and friction [N m]
  double polytropic_scale(double omega) const;  // n(omega) / gamma
  RotaryLoadMode mode_ = RotaryLoadMode::kStuck;
  HysteresisAnchor anchor_;
};

}  // namespace rigctl
