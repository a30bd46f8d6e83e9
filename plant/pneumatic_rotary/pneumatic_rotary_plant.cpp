#include "plant/pneumatic_rotary/pneumatic_rotary_plant.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "plant/pneumatic_rotary/coulomb_friction.hpp"
#include "plant/servo_valve.hpp"

namespace rigctl {

namespace {

// State vector layout.
constexpr std::size_t kTheta = 0, kOmega = 1, kPa = 2, kPb = 3;

}  // namespace

PneumaticRotaryPlant::PneumaticRotaryPlant(const PneumaticRotaryParams& params)
    : params_(params),
      signals_{{"theta", "rad"},       {"dp", "Pa"},    {"omega", "rad/s"},
               {"sim_pa", "Pa"},       {"sim_pb", "Pa"}, {"sim_x", "m"},
               {"sim_t_hysteresis", "N m"}, {"sim_t_friction", "N m"}},
      commands_{{"u", "V"}} {
  const auto& p = params_;
  hysteresis_ = bladder_hysteresis_levels(p.hysteresis, p.max_torque);
  brake_ = coulomb_brake_level(p.brake, p.max_torque);
  holding_ = hysteresis_.step + brake_;
  stick_slip_ = p.hysteresis.enabled || p.brake.enabled;
  gas_gain_ = p.heat_capacity_ratio * p.gas_constant * p.supply_temperature / p.chamber_volume;
  motion_gain_ = p.heat_capacity_ratio * p.quiescent_pressure * p.first_moment / p.chamber_volume;
  reset();
}

void PneumaticRotaryPlant::reset() {
  set_state(PneumaticRotaryState{});
  u_ = 0.0;
  bouc_wen_z_ = 0.0;
}

double PneumaticRotaryPlant::hidden_torque(double omega) const {
  const auto& f = params_.forms;
  double t = 0.0;
  if (f.bouc_wen_level > 0.0) t += f.bouc_wen_level * params_.max_torque * bouc_wen_z_;
  if (f.smooth_friction_level > 0.0) {
    constexpr double kBreakawayRatio = 1.3, kBreakawaySpeed = 0.02, kCoulombSpeed = 0.004;  // [1, rad/s, rad/s]
    const double fc = f.smooth_friction_level * params_.max_torque;
    const double v_st = kBreakawaySpeed * std::numbers::sqrt2;
    t += std::sqrt(2.0 * std::numbers::e) * (kBreakawayRatio - 1.0) * fc * std::exp(-(omega / v_st) * (omega / v_st)) *
             omega / v_st +
         fc * std::tanh(omega / kCoulombSpeed);
  }
  return t;
}

double PneumaticRotaryPlant::polytropic_scale(double omega) const {
  const auto& f = params_.forms;
  if (!(f.polytropic_slow > 0.0)) return 1.0;
  const double g = params_.heat_capacity_ratio, w = std::abs(omega);
  return (f.polytropic_slow + (g - f.polytropic_slow) * w / (w + f.polytropic_corner_speed)) / g;
}

PneumaticRotaryState PneumaticRotaryPlant::state() const {
  PneumaticRotaryState s;
  s.theta = y_[kTheta];
  s.omega = y_[kOmega];
  s.p_a = y_[kPa];
  s.p_b = y_[kPb];
  s.time = t_;
  s.mode = mode_;
  s.anchor = anchor_;
  return s;
}

void PneumaticRotaryPlant::set_state(const PneumaticRotaryState& s) {
  y_ = {s.theta, s.omega, s.p_a, s.p_b};
  t_ = s.time;
  mode_ = s.mode;
  anchor_ = s.anchor;
  if (stick_slip_ && s.omega != 0.0) mode_ = mode_for(s.omega > 0.0 ? 1 : -1);
}

double PneumaticRotaryPlant::spool_position(double u, double t) const {
  const auto& p = params_;
  double volts = u + p.valve_null_offset;
  if (p.dither) volts += p.dither_amplitude * std::sin(2.0 * std::numbers::pi * p.dither_frequency * t);
  return std::clamp(p.solenoid_gain * volts + p.forms.spool_null_shift, -p.spool_limit, p.spool_limit);
}

double PneumaticRotaryPlant::port_opening(double x) const {
  return overlapped_spool(x, params_.valve_overlap, params_.forms.overlap_edge_radius);
}

double PneumaticRotaryPlant::end_stop_torque(double theta, double omega) const {
  const auto& p = params_;
  // A stop can push but not pull: without the clamp the damper term would
  // hold the arm against the stop while it leaves.
  if (theta > p.angle_limit) {
    return std::min(0.0, -p.end_stop_stiffness * (theta - p.angle_limit) - p.end_stop_damping * omega);
  }
  if (theta < -p.angle_limit) {
    return std::max(0.0, -p.end_stop_stiffness * (theta + p.angle_limit) - p.end_stop_damping * omega);
  }
  return 0.0;
}

double PneumaticRotaryPlant::elastic_torque(double theta) const {
  return bladder_elastic_torque(hysteresis_, anchor_, theta);
}

// Everything on the load except the friction-like parts (step and brake).
double PneumaticRotaryPlant::residual_torque(const Vec& y) const {
  return params_.first_moment * (y[kPa] - y[kPb]) + end_stop_torque(y[kTheta], y[kOmega]) -
         elastic_torque(y[kTheta]);
}

void PneumaticRotaryPlant::derivatives(const Vec& y, double t, RotaryLoadMode mode, double u, Vec& dy) const {
  const auto& p = params_;
  const bool stuck = stick_slip_ && mode == RotaryLoadMode::kStuck;
  const double omega = stuck ? 0.0 : y[kOmega];

  const double x = port_opening(spool_position(u, t));
  const double m_a = p.flow_gain * x - p.flow_pressure_coefficient * y[kPa];
  const double m_b = -p.flow_gain * x - p.flow_pressure_coefficient * y[kPb];
  const double n_scale = polytropic_scale(omega);
  dy[kPa] = n_scale * (gas_gain_ * m_a - motion_gain_ * omega);
  dy[kPb] = n_scale * (gas_gain_ * m_b + motion_gain_ * omega);

  if (stuck) {
    dy[kTheta] = 0.0;
    dy[kOmega] = 0.0;
    return;
  }
  const double friction = stick_slip_ ? slide_direction(mode) * holding_ : 0.0;
  dy[kTheta] = omega;
  dy[kOmega] = (residual_torque(y) - friction - hidden_torque(omega)) / p.inertia;
}

void PneumaticRotaryPlant::rk4(Vec& y, double t, RotaryLoadMode mode, double u, double h) const {
  Vec k1, k2, k3, k4, s;
  derivatives(y, t, mode, u, k1);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y[i] + 0.5 * h * k1[i];
  derivatives(s, t + 0.5 * h, mode, u, k2);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y[i] + 0.5 * h * k2[i];
  derivatives(s, t + 0.5 * h, mode, u, k3);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y[i] + h * k3[i];
  derivatives(s, t + h, mode, u, k4);
  for (std::size_t i = 0; i < kN; ++i) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

RotaryLoadMode PneumaticRotaryPlant::mode_at_rest(const Vec& y) const {
  return mode_for(breakaway_direction(residual_torque(y), holding_));
}

// Every mode change starts a new monotone stretch: the hysteresis ramp is
// re-anchored where the load is now.
void PneumaticRotaryPlant::enter_mode(RotaryLoadMode mode) { enter_mode_at(mode, y_[kTheta]); }

void PneumaticRotaryPlant::enter_mode_at(RotaryLoadMode mode, double theta) {
  anchor_ = {theta, elastic_torque(theta)};
  mode_ = mode;
}

void PneumaticRotaryPlant::substep(double u, double h) {
  const double t0 = t_;
  if (params_.forms.bouc_wen_level > 0.0) {
    // The loop state is held over the RK4 stages and advanced once per
    // sub-step (explicit, with the sub-step's speed; bounded to [-1, 1]).
    const auto& f = params_.forms;
    const double w = y_[kOmega], z = bouc_wen_z_;
    const double sgn = (w * z > 0.0) ? 1.0 : -1.0;
    const double dz = w * h / f.bouc_wen_angle * (1.0 - (0.5 * sgn + 0.5) * std::pow(std::abs(z), f.bouc_wen_exponent));
    bouc_wen_z_ = std::clamp(z + dz, -1.0, 1.0);
  }
  if (!stick_slip_) {
    rk4(y_, t0, mode_, u, h);
    t_ = t0 + h;
    // Not used by the dynamics here; kept as the direction of motion so that
    // state() reads the same way with and without stick/slip.
    mode_ = mode_for(y_[kOmega] > 0.0 ? 1 : (y_[kOmega] < 0.0 ? -1 : 0));
    return;
  }
  if (mode_ == RotaryLoadMode::kStuck) {
    rk4(y_, t0, mode_, u, h);
    t_ = t0 + h;
    const RotaryLoadMode next = mode_at_rest(y_);
    if (next != mode_) enter_mode(next);
    return;
  }
  const Vec start = y_;
  const int dir = slide_direction(mode_);
  rk4(y_, t0, mode_, u, h);
  t_ = t0 + h;
  if (dir * y_[kOmega] > 0.0) return;

  // omega reached zero inside the step: redo the step up to the crossing so
  // that the stop or reversal (and the hysteresis step) happens where it
  // physically does, not at the next sub-step boundary.
  const double w0 = start[kOmega];
  const double w1 = y_[kOmega];
  double frac = dir * w0 > 0.0 ? w0 / (w0 - w1) : 0.0;
  frac = std::clamp(frac, 0.0, 1.0);
  y_ = start;
  if (frac > 0.0) rk4(y_, t0, mode_, u, frac * h);
  y_[kOmega] = 0.0;
  enter_mode(mode_at_rest(y_));
  const double rest = (1.0 - frac) * h;
  if (rest > 0.0) {
    rk4(y_, t0 + frac * h, mode_, u, rest);
    // The remainder is short: a second stop inside it is settled at its end.
    const int d = slide_direction(mode_);
    if (d == 0 || d * y_[kOmega] <= 0.0) {
      y_[kOmega] = 0.0;
      const RotaryLoadMode next = mode_at_rest(y_);
      if (next != mode_) enter_mode(next);
    }
  }
  t_ = t0 + h;
}

void PneumaticRotaryPlant::advance(std::span<const double> command, double dt) {
  if (!(dt > 0.0)) return;
  // A non-finite command must not poison the state; the driver flags it.
  const double u = held_command(command.empty() ? 0.0 : command[0]);
  u_ = u;
  const int n = std::max(1, params_.substeps);
  const double h = dt / n;
  for (int i = 0; i < n; ++i) substep(u, h);
}

double PneumaticRotaryPlant::hysteresis_torque() const {
  if (!params_.hysteresis.enabled) return 0.0;
  const double elastic = elastic_torque(y_[kTheta]);
  if (mode_ == RotaryLoadMode::kStuck) {
    return elastic + holding_share(residual_torque(y_), hysteresis_.step, holding_);
  }
  return elastic + slide_direction(mode_) * hysteresis_.step;
}

double PneumaticRotaryPlant::friction_torque() const {
  if (!params_.brake.enabled) return 0.0;
  if (mode_ == RotaryLoadMode::kStuck) return holding_share(residual_torque(y_), brake_, holding_);
  return slide_direction(mode_) * brake_;
}

void PneumaticRotaryPlant::measure(std::span<double> out) const {
  namespace sig = pneumatic_rotary_signal;
  std::array<double, sig::kCount> v{};
  v[sig::kTheta] = y_[kTheta];
  v[sig::kDp] = y_[kPa] - y_[kPb];
  v[sig::kOmega] = y_[kOmega];
  v[sig::kSimPa] = y_[kPa];
  v[sig::kSimPb] = y_[kPb];
  v[sig::kSimX] = spool_position(u_, t_);
  v[sig::kSimTHysteresis] = hysteresis_torque();
  v[sig::kSimTFriction] = friction_torque();
  const std::size_t n = std::min(out.size(), v.size());
  for (std::size_t i = 0; i < n; ++i) out[i] = v[i];
}

double PneumaticRotaryPlant::stored_energy() const {
  const auto& p = params_;
  const double kinetic = 0.5 * p.inertia * y_[kOmega] * y_[kOmega];
  double stop = 0.0;
  if (y_[kTheta] > p.angle_limit) stop = y_[kTheta] - p.angle_limit;
  if (y_[kTheta] < -p.angle_limit) stop = y_[kTheta] + p.angle_limit;
  const double spring = 0.5 * p.end_stop_stiffness * stop * stop;
  const double elastic = elastic_torque(y_[kTheta]);
  const double ramp = hysteresis_.stiffness > 0.0 ? elastic * elastic / (2.0 * hysteresis_.stiffness) : 0.0;
  const double gas = p.chamber_volume * (y_[kPa] * y_[kPa] + y_[kPb] * y_[kPb]) /
                     (2.0 * p.heat_capacity_ratio * p.quiescent_pressure);
  return kinetic + spring + ramp + gas;
}

}  // namespace rigctl
