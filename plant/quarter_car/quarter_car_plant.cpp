#include "plant/quarter_car/quarter_car_plant.hpp"

#include "plant/quarter_car/hidden_effect_laws.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "plant/quarter_car/quarter_car_step_size.hpp"
#include "plant/servo_valve.hpp"

namespace rigctl {

namespace {

// State vector layout.
constexpr std::size_t kXs = 0, kP1 = 1, kP2 = 2, kXr = 3, kVr = 4, kXw = 5, kVw = 6, kXb = 7,
                      kVb = 8;

// Only reachable if the end stop is overrun by more than the dead volume;
// keeps beta/V finite instead of dividing by zero or a negative volume.
constexpr double kMinVolume = 1e-9;

// exp(x) - 1 - x without the cancellation of the direct form at small x
// (oil energies are ~1e-2 of P V, and the energy test resolves 1e-9 of them).
double expm1_minus_x(double x) {
  if (std::abs(x) > 0.5) return std::expm1(x) - x;
  double term = 0.5 * x * x;
  double sum = term;
  for (int k = 3; k < 30 && std::abs(term) > 1e-18 * std::abs(sum); ++k) {
    term *= x / k;
    sum += term;
  }
  return sum;
}

}  // namespace

QuarterCarPlant::QuarterCarPlant(const QuarterCarParams& params)
    : params_(params),
      fastest_rate_(quarter_car_fastest_rate(params)),
      signals_{{"x_r", "m"},       {"x_w", "m"},          {"x_b", "m"},
               {"v_w", "m/s"},     {"v_b", "m/s"},        {"p1", "Pa"},
               {"p2", "Pa"},       {"f_t", "N"},          {"sim_v_r", "m/s"},
               {"sim_x_s", "1"},   {"sim_f_bearing", "N"}, {"sim_bearing_stuck", "1"}},
      commands_{{"u", "1"}} {
  // One bearing friction law at a time: the stick/slip sub-step would never
  // advance the LuGre bristles (substep() below).
  if (params.hidden.bearing_lugre && params.bearing_friction.enabled) {
    throw std::invalid_argument("quarter car: the LuGre bearing friction (hidden.bearing_lugre) and the stick/slip "
                                "bearing friction (bearing_friction.enabled) cannot both be on");
  }
  reset();
}

double QuarterCarPlant::rest_valve_offset(const QuarterCarParams& p) {
  if (!p.leakage) return 0.0;
  const QuarterCarState rest = rest_state(p);
  return rest.x_s;
}

QuarterCarState QuarterCarPlant::rest_state(const QuarterCarParams& p) {
  QuarterCarState s;
  const double weight = (p.mass_rod + p.mass_wheel + p.mass_body) * p.gravity;
  if (p.leakage) {
    // P1 + P2 = Ps holds because the valve then meters the same leakage flow
    // in through one edge and out through the other: Ps - P2 = P1 makes the
    // supply-edge and tank-edge flows equal for one spool position.
    s.p1 = (weight + p.supply_pressure * p.area_rod) / (p.area_cap + p.area_rod);
    s.p2 = p.supply_pressure - s.p1;
    const double leak = (s.p1 - s.p2) / p.leakage_resistance;
    // Spool >= 0 feeds side 1 through Ps - P1 = P2; spool < 0 drains it through P1.
    const double root = orifice_root(leak >= 0.0 ? s.p2 : s.p1, p.laminar_pressure);
    const double gain = p.valve_flow_gain * root;
    s.x_s = gain != 0.0 ? leak / gain : 0.0;
  } else {
    s.p1 = s.p2 = weight / (p.area_cap - p.area_rod);
    s.x_s = 0.0;
  }
  s.bearing = BearingMode::kStuck;
  return s;
}

void QuarterCarPlant::reset() {
  supply_pressure_ = params_.supply_pressure;
  chamber_leak_ = {};
  lugre_z_ = 0.0;
  set_state(rest_state(params_));
}

QuarterCarState QuarterCarPlant::state() const {
  QuarterCarState s;
  s.x_s = y_[kXs];
  s.p1 = y_[kP1];
  s.p2 = y_[kP2];
  s.x_r = y_[kXr];
  s.v_r = y_[kVr];
  s.x_w = y_[kXw];
  s.v_w = y_[kVw];
  s.x_b = y_[kXb];
  s.v_b = y_[kVb];
  s.bearing = mode_;
  return s;
}

void QuarterCarPlant::set_state(const QuarterCarState& s) {
  y_ = to_vec(s);
  mode_ = s.bearing;
  if (params_.bearing_friction.enabled && s.v_b != 0.0) mode_ = sliding_mode(s.v_b);
}

double QuarterCarPlant::end_stop_force(double x_r, double v_r) const {
  const auto& p = params_;
  // A contact can push but not pull: without the clamp the damper term would
  // hold the rod against the stop while it leaves.
  if (x_r < p.stroke_min) {
    return std::max(0.0, -p.end_stop_stiffness * (x_r - p.stroke_min) - p.end_stop_damping * v_r);
  }
  if (x_r > p.stroke_max) {
    return std::min(0.0, -p.end_stop_stiffness * (x_r - p.stroke_max) - p.end_stop_damping * v_r);
  }
  return 0.0;
}

double QuarterCarPlant::suspension_force(const Vec& y) const {
  const auto& p = params_;
  return p.spring_stiffness * (y[kXw] - y[kXb]) + damper_force(p.damper_damping, p.hidden, y[kVw] - y[kVb]);
}

double QuarterCarPlant::tyre_force(const Vec& y) const {
  const auto& p = params_;
  const double spring = (p.mass_body + p.mass_wheel) * p.gravity + p.tyre_stiffness * (y[kXr] - y[kXw]);
  if (p.hidden.tyre_damping_in_contact_only && spring < 0.0) return (1.0 - p.hidden.tyre_pull_loss) * spring;
  const double f = spring + p.tyre_damping * (y[kVr] - y[kVw]);
  return f < 0.0 ? (1.0 - p.hidden.tyre_pull_loss) * f : f;
}

double QuarterCarPlant::seal_friction(double v, double p1, double p2) const {
  return seal_friction_force(params_.hidden, v, p1, p2);
}

double QuarterCarPlant::effective_bulk_modulus(double p) const {
  return mixture_bulk_modulus(params_.bulk_modulus, params_.hidden.air_fraction, params_.hidden.air_polytropic_index, p);
}

LugreLevels QuarterCarPlant::lugre_levels(const Vec& y) const {
  const auto& b = params_.bearing_friction;
  const auto lv = levels_at(y);
  return {lv.coulomb, lv.breakaway, b.stribeck_velocity, b.viscous, params_.hidden.lugre_sigma0,
          params_.hidden.lugre_sigma1};
}

BearingFrictionLevels QuarterCarPlant::levels_at(const Vec& y) const {
  const auto& p = params_;
  const double deflection = y[kXw] - y[kXb];
  const double f_susp = suspension_force(y);
  return bearing_friction_levels(p.bearing_friction, p.mass_body * p.gravity, f_susp, deflection);
}

void QuarterCarPlant::derivatives(const Vec& y, BearingMode mode, double u, Vec& dy) const {
  const auto& p = params_;
  const double f0 = (p.mass_body + p.mass_wheel) * p.gravity;

  dy[kXs] = (u - y[kXs]) / p.valve_time_constant;

  const double spool = overlapped_spool(y[kXs], p.hidden.valve_overlap, p.hidden.valve_overlap_edge_radius);
  const ValveFlows q = valve_flows(spool, y[kP1], y[kP2], p.valve_flow_gain, supply_pressure_, p.laminar_pressure);
  double q_leak = (p.leakage ? (y[kP1] - y[kP2]) / p.leakage_resistance : 0.0) +
                  p.hidden.extra_laminar_leak * (y[kP1] - y[kP2]);
  if (p.hidden.worn_seal_orifice > 0.0) {
    q_leak += p.hidden.worn_seal_orifice * orifice_root(y[kP1] - y[kP2], p.laminar_pressure);
  }
  const double v1 = std::max(p.dead_volume_cap + p.area_cap * (y[kXr] - p.stroke_min), kMinVolume);
  const double v2 = std::max(p.dead_volume_rod + p.area_rod * (p.stroke_max - y[kXr]), kMinVolume);
  // Burst pipes (fault injection): each chamber spills to tank.
  const double q_burst1 = chamber_leak_[0] > 0.0 ? chamber_leak_[0] * orifice_root(std::max(y[kP1], 0.0), p.laminar_pressure) : 0.0;
  const double q_burst2 = chamber_leak_[1] > 0.0 ? chamber_leak_[1] * orifice_root(std::max(y[kP2], 0.0), p.laminar_pressure) : 0.0;
  double dp1 = effective_bulk_modulus(y[kP1]) / v1 * (q.q1 - p.area_cap * y[kVr] - q_leak - q_burst1);
  double dp2 = effective_bulk_modulus(y[kP2]) / v2 * (p.area_rod * y[kVr] + q_leak - q.q2 - q_burst2);
  // At the cavitation floor the oil releases vapour instead of stretching.
  if (y[kP1] <= p.cavitation_pressure && dp1 < 0.0) dp1 = 0.0;
  if (y[kP2] <= p.cavitation_pressure && dp2 < 0.0) dp2 = 0.0;
  dy[kP1] = dp1;
  dy[kP2] = dp2;

  const double f_tyre = tyre_force(y);
  const double f_susp = suspension_force(y);

  dy[kXr] = y[kVr];
  dy[kVr] = (y[kP1] * p.area_cap - y[kP2] * p.area_rod - p.rod_damping * y[kVr] - f_tyre -
             p.mass_rod * p.gravity + end_stop_force(y[kXr], y[kVr]) - seal_friction(y[kVr], y[kP1], y[kP2])) /
            p.mass_rod;
  dy[kXw] = y[kVw];
  dy[kVw] = (f_tyre - f0 - f_susp) / p.mass_wheel;

  if (p.hidden.bearing_lugre) {
    dy[kXb] = y[kVb];
    dy[kVb] = (f_susp - lugre_force(lugre_levels(y), lugre_z_, y[kVb])) / p.mass_body;
  } else if (!p.bearing_friction.enabled) {
    dy[kXb] = y[kVb];
    dy[kVb] = f_susp / p.mass_body;
  } else if (mode == BearingMode::kStuck) {
    dy[kXb] = 0.0;
    dy[kVb] = 0.0;
  } else {
    const double f_bearing =
        sliding_friction(p.bearing_friction, levels_at(y), slide_direction(mode), y[kVb]);
    dy[kXb] = y[kVb];
    dy[kVb] = (f_susp - f_bearing) / p.mass_body;
  }
}

void QuarterCarPlant::rk4(Vec& y, BearingMode mode, double u, double h) const {
  Vec k1, k2, k3, k4, t;
  derivatives(y, mode, u, k1);
  for (std::size_t i = 0; i < kN; ++i) t[i] = y[i] + 0.5 * h * k1[i];
  derivatives(t, mode, u, k2);
  for (std::size_t i = 0; i < kN; ++i) t[i] = y[i] + 0.5 * h * k2[i];
  derivatives(t, mode, u, k3);
  for (std::size_t i = 0; i < kN; ++i) t[i] = y[i] + h * k3[i];
  derivatives(t, mode, u, k4);
  for (std::size_t i = 0; i < kN; ++i) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  apply_floors(y);
}

void QuarterCarPlant::apply_floors(Vec& y) const {
  y[kP1] = std::max(y[kP1], params_.cavitation_pressure);
  y[kP2] = std::max(y[kP2], params_.cavitation_pressure);
}

BearingMode QuarterCarPlant::mode_at_rest(const Vec& y) const {
  const double f_susp = suspension_force(y);
  if (std::abs(f_susp) > levels_at(y).breakaway) return sliding_mode(f_susp);
  return BearingMode::kStuck;
}

// Mode bookkeeping at a sub-step boundary without locating anything: a stuck
// bearing breaks away, a sliding one that has come to rest sticks or reverses.
void QuarterCarPlant::settle_mode() {
  if (mode_ == BearingMode::kStuck) {
    mode_ = mode_at_rest(y_);
    return;
  }
  if (slide_direction(mode_) * y_[kVb] <= 0.0) {
    y_[kVb] = 0.0;
    mode_ = mode_at_rest(y_);
  }
}

void QuarterCarPlant::substep(double u, double h) {
  if (!params_.bearing_friction.enabled) {
    const double vb0 = y_[kVb];
    rk4(y_, mode_, u, h);
    // The bristle state is held over the RK4 stages and advanced exactly at
    // the step's mean body velocity (it is far stiffer than the step).
    if (params_.hidden.bearing_lugre)
      lugre_z_ = lugre_advance(lugre_levels(y_), lugre_z_, 0.5 * (vb0 + y_[kVb]), h);
    return;
  }
  if (mode_ == BearingMode::kStuck) {
    rk4(y_, mode_, u, h);
    settle_mode();
    return;
  }
  const Vec start = y_;
  const int dir = slide_direction(mode_);
  rk4(y_, mode_, u, h);
  if (dir * y_[kVb] > 0.0) return;

  // v_b reached zero inside the step: redo the step up to the crossing so
  // that the reversal or stop happens where it physically does.
  const double v0 = start[kVb];
  const double v1 = y_[kVb];
  double frac = dir * v0 > 0.0 ? v0 / (v0 - v1) : 0.0;
  frac = std::clamp(frac, 0.0, 1.0);
  y_ = start;
  if (frac > 0.0) rk4(y_, mode_, u, frac * h);
  y_[kVb] = 0.0;
  mode_ = mode_at_rest(y_);
  const double rest = (1.0 - frac) * h;
  if (rest > 0.0) {
    rk4(y_, mode_, u, rest);
    settle_mode();
  }
}

void QuarterCarPlant::advance(std::span<const double> command, double dt) {
  if (!(dt > 0.0)) return;
  // A non-finite command must not poison the state; the driver flags it.
  const double u = held_command(command.empty() ? 0.0 : command[0]);
  const int n = quarter_car_substeps(params_, fastest_rate_, dt);
  const double h = dt / n;
  for (int i = 0; i < n; ++i) substep(u, h);
}

double QuarterCarPlant::tyre_force() const { return tyre_force(y_); }

double QuarterCarPlant::suspension_force() const { return suspension_force(y_); }

BearingFrictionLevels QuarterCarPlant::bearing_levels() const { return levels_at(y_); }

double QuarterCarPlant::bearing_force() const {
  const auto& p = params_;
  if (p.hidden.bearing_lugre) return lugre_force(lugre_levels(y_), lugre_z_, y_[kVb]);
  if (!p.bearing_friction.enabled) return 0.0;
  if (mode_ == BearingMode::kStuck) return suspension_force();
  return sliding_friction(p.bearing_friction, levels_at(y_), slide_direction(mode_), y_[kVb]);
}

void QuarterCarPlant::measure(std::span<double> out) const {
  namespace sig = quarter_car_signal;
  std::array<double, sig::kCount> v{};
  v[sig::kXr] = y_[kXr];
  v[sig::kXw] = y_[kXw];
  v[sig::kXb] = y_[kXb];
  v[sig::kVw] = y_[kVw];
  v[sig::kVb] = y_[kVb];
  v[sig::kP1] = y_[kP1];
  v[sig::kP2] = y_[kP2];
  v[sig::kFt] = tyre_force();
  v[sig::kSimVr] = y_[kVr];
  v[sig::kSimXs] = y_[kXs];
  v[sig::kSimFBearing] = bearing_force();
  v[sig::kSimBearingStuck] =
      params_.bearing_friction.enabled && mode_ == BearingMode::kStuck ? 1.0 : 0.0;
  const std::size_t n = std::min(out.size(), v.size());
  for (std::size_t i = 0; i < n; ++i) out[i] = v[i];
}

double QuarterCarPlant::total_energy() const {
  const auto& p = params_;
  const double weight = (p.mass_rod + p.mass_wheel + p.mass_body) * p.gravity;
  const double kinetic = 0.5 * (p.mass_rod * y_[kVr] * y_[kVr] + p.mass_wheel * y_[kVw] * y_[kVw] +
                                p.mass_body * y_[kVb] * y_[kVb]);
  const double tyre = y_[kXr] - y_[kXw];
  const double spring = y_[kXw] - y_[kXb];
  double stop = 0.0;
  if (y_[kXr] < p.stroke_min) stop = y_[kXr] - p.stroke_min;
  if (y_[kXr] > p.stroke_max) stop = y_[kXr] - p.stroke_max;
  const double potential = weight * y_[kXr] + 0.5 * p.tyre_stiffness * tyre * tyre +
                           0.5 * p.spring_stiffness * spring * spring +
                           0.5 * p.end_stop_stiffness * stop * stop;
  const double v1 = std::max(p.dead_volume_cap + p.area_cap * (y_[kXr] - p.stroke_min), kMinVolume);
  const double v2 = std::max(p.dead_volume_rod + p.area_rod * (p.stroke_max - y_[kXr]), kMinVolume);
  const double beta = p.bulk_modulus;
  const double oil = v1 * beta * expm1_minus_x(y_[kP1] / beta) +
                     v2 * beta * expm1_minus_x(y_[kP2] / beta);
  return kinetic + potential + oil;
}

}  // namespace rigctl
