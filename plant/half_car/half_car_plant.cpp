#include "plant/half_car/half_car_plant.hpp"

#include <algorithm>
#include <cmath>

namespace rigctl {

namespace {

// State vector layout.
constexpr std::size_t kZs = 0, kPhi = 1, kZu1 = 2, kZu2 = 3, kVs = 4, kOmega = 5, kVu1 = 6, kVu2 = 7, kF1 = 8,
                      kF2 = 9, kValve1 = 10, kValve2 = 11;

WheelArrangement arrangement_of(const HalfCarParams& p) {
  return p.plane == HalfCarPlane::kPitch ? WheelArrangement::kInLine : WheelArrangement::kSideBySide;
}

double wheelbase_of(const HalfCarParams& p) { return p.plane == HalfCarPlane::kPitch ? p.dist_front + p.dist_rear : 0.0; }

}  // namespace

HalfCarPlant::HalfCarPlant(const HalfCarParams& params)
    : params_((validate(params), params)),
      road_(params.road, params.speed, arrangement_of(params), wheelbase_of(params)),
      signals_{{"z_r1", "m"},
               {"z_r2", "m"},
               {"z_s", "m"},
               {"phi", "rad"},
               {"z_u1", "m"},
               {"z_u2", "m"},
               {"z_s_dot", "m/s"},
               {"z_s_ddot", "m/s^2"},
               {"phi_dot", "rad/s"},
               {"phi_ddot", "rad/s^2"},
               {"z_u1_dot", "m/s"},
               {"z_u2_dot", "m/s"},
               {"susp_travel_1", "m"},
               {"susp_travel_2", "m"},
               {"sim_tyre_force_1", "N"},
               {"sim_tyre_force_2", "N"},
               {"sim_contact_1", "1"},
               {"sim_contact_2", "1"},
               {"sim_f_act_1", "N"},
               {"sim_f_act_2", "N"},
               {"sim_m_roll", "N m"}},
      commands_{{"f_1", "N"}, {"f_2", "N"}} {
  const double kt[2] = {params_.tyre_stiffness_1, params_.tyre_stiffness_2};
  for (int i = 0; i < 2; ++i) {
    const auto k = static_cast<std::size_t>(i);
    lever_[k] = half_car_lever_arm(params_, i);
    static_load_[k] = half_car_static_tyre_load(params_, i);
    free_compression_[k] = static_load_[k] / kt[i];
  }
  roll_moment_full_ = half_car_roll_moment(params_);
  reset();
}

void HalfCarPlant::reset() {
  set_state(HalfCarState{});
  u_ = {0.0, 0.0};
}

HalfCarState HalfCarPlant::state() const {
  return {y_[kZs], y_[kPhi], y_[kZu1], y_[kZu2], y_[kVs], y_[kOmega], y_[kVu1], y_[kVu2], y_[kF1], y_[kF2], t_,
          y_[kValve1], y_[kValve2]};
}

void HalfCarPlant::set_state(const HalfCarState& s) {
  y_ = to_vec(s);
  t_ = s.time;
  u_ = {s.f_act1, s.f_act2};
}

double HalfCarPlant::roll_moment(double t) const {
  if (roll_moment_full_ == 0.0) return 0.0;
  const double since = t - params_.curve_start_time;
  if (since < 0.0) return 0.0;
  if (params_.curve_ramp_time > 0.0 && since < params_.curve_ramp_time) {
    return roll_moment_full_ * since / params_.curve_ramp_time;
  }
  return roll_moment_full_;
}

double HalfCarPlant::tyre_force_at(const Vec& y, int wheel, double t) const {
  const auto k = static_cast<std::size_t>(wheel);
  const RoadSample r = road_.at(wheel, t);
  const double zu = y[kZu1 + k];
  if (free_compression_[k] + r.z - zu <= 0.0) return 0.0;  // lifted off
  const double kt = wheel == 0 ? params_.tyre_stiffness_1 : params_.tyre_stiffness_2;
  const double ct = wheel == 0 ? params_.tyre_damping_1 : params_.tyre_damping_2;
  // Static load plus the change (written so that it is exactly F0 at rest).
  return std::max(0.0, static_load_[k] + kt * (r.z - zu) + ct * (r.dz - y[kVu1 + k]));
}

// Rebound (rate > 0) damping is damper_rebound_factor times compression;
// past damper_rebound_knee the rebound force grows at a third of that rate
// (a digressive valve opening).
double HalfCarPlant::damper_force(double c, double rate) const {
  const auto& p = params_;
  if (rate <= 0.0) return c * rate;
  const double cr = c * p.damper_rebound_factor, knee = p.damper_rebound_knee;
  if (knee <= 0.0 || rate <= knee) return cr * rate;
  return cr * (knee + (rate - knee) / 3.0);
}

void HalfCarPlant::derivatives(const Vec& y, double t, const Command2& u, Vec& dy) const {
  const auto& p = params_;
  const double k[2] = {p.spring_1, p.spring_2};
  const double c[2] = {p.damper_1, p.damper_2};
  const double mu[2] = {p.mass_unsprung_1, p.mass_unsprung_2};

  double heave = 0.0;
  double moment = roll_moment(t);
  for (std::size_t i = 0; i < 2; ++i) {
    const double l = lever_[i];
    const double travel = y[kZs] + l * y[kPhi] - y[kZu1 + i];
    const double rate = y[kVs] + l * y[kOmega] - y[kVu1 + i];
    const double f_body = -k[i] * travel - damper_force(c[i], rate) + y[kF1 + i];
    heave += f_body;
    moment += l * f_body;
    // The tyre's change from its static load; the static loads balance gravity.
    const double tyre = tyre_force_at(y, static_cast<int>(i), t) - static_load_[i];
    dy[kZu1 + i] = y[kVu1 + i];
    dy[kVu1 + i] = (tyre - f_body) / mu[i];
  }
  dy[kZs] = y[kVs];
  dy[kPhi] = y[kOmega];
  dy[kVs] = heave / p.mass_body;
  dy[kOmega] = moment / p.inertia_body;
  dy[kF1] = dy[kF2] = dy[kValve1] = dy[kValve2] = 0.0;
  if (p.actuator_time_constant > 0.0) {
    const bool valve = p.actuator_valve_time_constant > 0.0;
    for (std::size_t i = 0; i < 2; ++i) {
      // Command -> valve stage (tau2) -> force loop (tau1); without the valve
      // stage the force loop follows the command directly.
      const double drive = valve ? y[kValve1 + i] : u[i];
      dy[kF1 + i] = (drive - y[kF1 + i]) / p.actuator_time_constant;
      if (valve) dy[kValve1 + i] = (u[i] - y[kValve1 + i]) / p.actuator_valve_time_constant;
    }
  }
}

void HalfCarPlant::rk4(double h) {
  Vec k1, k2, k3, k4, s;
  derivatives(y_, t_, u_, k1);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y_[i] + 0.5 * h * k1[i];
  derivatives(s, t_ + 0.5 * h, u_, k2);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y_[i] + 0.5 * h * k2[i];
  derivatives(s, t_ + 0.5 * h, u_, k3);
  for (std::size_t i = 0; i < kN; ++i) s[i] = y_[i] + h * k3[i];
  derivatives(s, t_ + h, u_, k4);
  for (std::size_t i = 0; i < kN; ++i) y_[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  t_ += h;
}

void HalfCarPlant::advance(std::span<const double> command, double dt) {
  if (!(dt > 0.0)) return;
  u_ = held_command(command);
  hold_command(u_, y_);
  const int n = std::max(1, params_.substeps);
  const double h = dt / n;
  for (int i = 0; i < n; ++i) rk4(h);
}

HalfCarPlant::Command2 HalfCarPlant::held_command(std::span<const double> command) const {
  Command2 u{};
  for (std::size_t i = 0; i < 2; ++i) {
    double v = i < command.size() ? command[i] : 0.0;
    // A non-finite command must not poison the state; the driver flags it.
    if (!std::isfinite(v)) v = 0.0;
    if (params_.actuator_force_limit > 0.0) {
      v = std::clamp(v, -params_.actuator_force_limit, params_.actuator_force_limit);
    }
    u[i] = v;
  }
  return u;
}

void HalfCarPlant::hold_command(const Command2& u, Vec& y) const {
  for (std::size_t i = 0; i < 2; ++i) {
    if (params_.actuator_time_constant <= 0.0) y[kF1 + i] = u[i];  // ideal force source
    if (params_.actuator_valve_time_constant <= 0.0) y[kValve1 + i] = u[i];  // no valve stage: it passes the command
  }
}

double HalfCarPlant::tyre_force(int wheel) const { return tyre_force_at(y_, wheel, t_); }

bool HalfCarPlant::in_contact(int wheel) const {
  const auto k = static_cast<std::size_t>(wheel);
  return free_compression_[k] + road_.height(wheel, t_) - y_[kZu1 + k] > 0.0;
}

void HalfCarPlant::measure(std::span<double> out) const {
  namespace sig = half_car_signal;
  Vec dy;
  derivatives(y_, t_, u_, dy);
  std::array<double, sig::kCount> v{};
  v[sig::kZr1] = road_.height(0, t_);
  v[sig::kZr2] = road_.height(1, t_);
  v[sig::kZs] = y_[kZs];
  v[sig::kPhi] = y_[kPhi];
  v[sig::kZu1] = y_[kZu1];
  v[sig::kZu2] = y_[kZu2];
  v[sig::kZsDot] = y_[kVs];
  v[sig::kZsDdot] = dy[kVs];
  v[sig::kPhiDot] = y_[kOmega];
  v[sig::kPhiDdot] = dy[kOmega];
  v[sig::kZu1Dot] = y_[kVu1];
  v[sig::kZu2Dot] = y_[kVu2];
  v[sig::kTravel1] = y_[kZs] + lever_[0] * y_[kPhi] - y_[kZu1];
  v[sig::kTravel2] = y_[kZs] + lever_[1] * y_[kPhi] - y_[kZu2];
  v[sig::kSimTyreForce1] = tyre_force(0);
  v[sig::kSimTyreForce2] = tyre_force(1);
  v[sig::kSimContact1] = in_contact(0) ? 1.0 : 0.0;
  v[sig::kSimContact2] = in_contact(1) ? 1.0 : 0.0;
  v[sig::kSimFAct1] = y_[kF1];
  v[sig::kSimFAct2] = y_[kF2];
  v[sig::kSimMRoll] = roll_moment(t_);
  const std::size_t n = std::min(out.size(), v.size());
  for (std::size_t i = 0; i < n; ++i) out[i] = v[i];
}

}  // namespace rigctl
