// Reference solutions of the plants with Boost.Odeint (see bench_reference.hpp).
#include "tools/bench_reference.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <boost/numeric/odeint.hpp>

#include "plant/bearing_friction.hpp"
#include "plant/bladder_hysteresis.hpp"
#include "plant/coulomb_friction.hpp"
#include "plant/servo_valve.hpp"

namespace rigctl::bench {

namespace odeint = boost::numeric::odeint;

namespace {

constexpr double kNoEvent = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------
// A hybrid integrator: adaptive Dormand-Prince within a mode; a model's event
// function going from > 0 to <= 0 inside an accepted step is located by
// bisection (each trial a single Dormand-Prince step from the step's start,
// so no interpolation error enters), then the model switches mode there.
//
// Model interface:
//   using Vec = std::array<double, N>;
//   void rhs(const Vec& y, Vec& dy, double t) const;    // current mode and command
//   double event(const Vec& y, double t) const;         // kNoEvent when none can happen
//   void on_event(Vec& y, double t);                    // switch mode (may change y)
//   bool post_step(Vec& y) const;                       // floors; true when y changed
template <class Model>
class HybridIntegrator {
 public:
  using Vec = typename Model::Vec;

  HybridIntegrator(Model& model, double tolerance, ReferenceStats& stats)
      : model_(model), controlled_(odeint::make_controlled(tolerance, tolerance, Dopri())), stats_(stats) {}

  // Integrates from t to t_end (the command is constant in between).
  void advance(Vec& y, double& t, double t_end) {
    Vec dydt;
    eval(y, dydt, t);
    while (t < t_end) {
      const bool last = dt_ >= t_end - t;
      double dt = last ? t_end - t : dt_;
      const Vec y_old = y;
      const Vec dydt_old = dydt;
      const double t_old = t;
      if (controlled_.try_step(system(), y, dydt, t, dt) == odeint::fail) {
        ++stats_.rejected;
        dt_ = dt;  // the smaller step it suggests
        if (dt_ < 1e-15) throw std::runtime_error("reference integrator: step size underflow");
        continue;
      }
      ++stats_.steps;
      // try_step suggests the next step in dt; a step clipped to the period
      // end says nothing about the step size the dynamics allow.
      if (!last || dt > dt_) dt_ = dt;
      if (last) t = t_end;
      bool changed = model_.post_step(y);

      const double g_old = model_.event(y_old, t_old);
      const double g_new = model_.event(y, t);
      if (g_new <= 0.0 && g_old > 0.0) {
        locate(y_old, dydt_old, t_old, t - t_old, y, t);
        model_.post_step(y);
        model_.on_event(y, t);
        ++stats_.events;
        changed = true;
      } else if (g_new <= 0.0 && g_old <= 0.0 && g_new != kNoEvent) {
        // Started on the switching surface and went the wrong way (a
        // sliding body that decelerates at once): settle at the step end,
        // as the plant does.
        model_.on_event(y, t);
        ++stats_.events;
        changed = true;
      }
      if (changed) eval(y, dydt, t);
    }
  }

 private:
  using Dopri = odeint::runge_kutta_dopri5<Vec>;

  auto system() {
    return [this](const Vec& y, Vec& dy, double t) { eval(y, dy, t); };
  }
  void eval(const Vec& y, Vec& dy, double t) {
    ++stats_.rhs_evaluations;
    model_.rhs(y, dy, t);
  }

  // Bisection on the step size from (y0, t0): the smallest step found after
  // which the event function is <= 0.
  void locate(const Vec& y0, const Vec& dydt0, double t0, double h, Vec& y, double& t) {
    double lo = 0.0, hi = h;
    Vec trial, dydt_out;
    Vec at_hi = y;
    for (int i = 0; i < 80 && hi - lo > 1e-13; ++i) {
      const double mid = 0.5 * (lo + hi);
      single_.do_step(system(), y0, dydt0, t0, trial, dydt_out, mid);
      model_.post_step(trial);
      if (model_.event(trial, t0 + mid) <= 0.0) {
        hi = mid;
        at_hi = trial;
      } else {
        lo = mid;
      }
    }
    y = at_hi;
    t = t0 + hi;
  }

  Model& model_;
  decltype(odeint::make_controlled(1.0, 1.0, Dopri())) controlled_;
  Dopri single_;
  ReferenceStats& stats_;
  double dt_ = 1e-6;
};

template <class Model, class Finish>
ReferenceResult run_reference(Model& model, typename Model::Vec y, const CommandSeries& u, double period_s,
                              double tolerance, const std::atomic<bool>& stop, Finish&& to_vector) {
  ReferenceResult r;
  r.stats.tolerance = tolerance;
  HybridIntegrator<Model> integrator(model, tolerance, r.stats);
  const auto start = std::chrono::steady_clock::now();
  double t = 0.0;
  r.at.reserve(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (stop.load()) break;
    model.set_command(u[k], y);
    const double t_end = static_cast<double>(k + 1) * period_s;
    integrator.advance(y, t, t_end);
    r.at.push_back(to_vector(y));
  }
  r.stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.completed = r.at.size() == u.size();
  return r;
}

// One classical RK4 step with the model's right-hand side (what the plants do
// in one sub-step), for the agreement check.
template <class Model>
typename Model::Vec rk4_step(const Model& m, typename Model::Vec y, double t, double h) {
  using Vec = typename Model::Vec;
  const std::size_t n = y.size();
  Vec k1, k2, k3, k4, s;
  m.rhs(y, k1, t);
  for (std::size_t i = 0; i < n; ++i) s[i] = y[i] + 0.5 * h * k1[i];
  m.rhs(s, k2, t + 0.5 * h);
  for (std::size_t i = 0; i < n; ++i) s[i] = y[i] + 0.5 * h * k2[i];
  m.rhs(s, k3, t + 0.5 * h);
  for (std::size_t i = 0; i < n; ++i) s[i] = y[i] + h * k3[i];
  m.rhs(s, k4, t + h);
  for (std::size_t i = 0; i < n; ++i) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  m.post_step(y);
  return y;
}

// Relative difference of two results of a step from y0: measured against the
// size of the step's change (plus a rounding floor), component by component.
template <class Vec>
double step_difference(const Vec& y0, const Vec& a, const std::vector<double>& b) {
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double scale = std::abs(b[i] - y0[i]) + 1e-12 * std::abs(y0[i]) + 1e-300;
    worst = std::max(worst, std::abs(a[i] - b[i]) / scale);
  }
  return worst;
}

// ---------------------------------------------------------------------------
// Quarter car (plant/quarter_car_plant.cpp, derivatives() and substep()).

namespace qc {
constexpr std::size_t kXs = 0, kP1 = 1, kP2 = 2, kXr = 3, kVr = 4, kXw = 5, kVw = 6, kXb = 7, kVb = 8;
constexpr double kMinVolume = 1e-9;
}  // namespace qc

struct QuarterCarModel {
  using Vec = std::array<double, 9>;

  explicit QuarterCarModel(const QuarterCarParams& params) : p(params) {}

  QuarterCarParams p;
  BearingMode mode = BearingMode::kStuck;
  double u = 0.0;

  static int direction(BearingMode m) { return m == BearingMode::kSlidingDown ? -1 : 1; }
  static BearingMode sliding(double force) {
    return force >= 0.0 ? BearingMode::kSlidingUp : BearingMode::kSlidingDown;
  }

  void set_command(const HeldCommand& c, Vec&) {
    double v = c[0];
    if (!std::isfinite(v)) v = 0.0;
    u = std::clamp(v, -1.0, 1.0);
  }

  double f_susp(const Vec& y) const {
    return p.spring_stiffness * (y[qc::kXw] - y[qc::kXb]) + p.damper_damping * (y[qc::kVw] - y[qc::kVb]);
  }
  BearingFrictionLevels levels(const Vec& y) const {
    return bearing_friction_levels(p.bearing_friction, p.mass_body * p.gravity, f_susp(y), y[qc::kXw] - y[qc::kXb]);
  }
  double end_stop(double x_r, double v_r) const {
    if (x_r < p.stroke_min) return std::max(0.0, -p.end_stop_stiffness * (x_r - p.stroke_min) - p.end_stop_damping * v_r);
    if (x_r > p.stroke_max) return std::min(0.0, -p.end_stop_stiffness * (x_r - p.stroke_max) - p.end_stop_damping * v_r);
    return 0.0;
  }

  void rhs(const Vec& y, Vec& dy, double) const {
    using namespace qc;
    const double f0 = (p.mass_body + p.mass_wheel) * p.gravity;
    dy[kXs] = (u - y[kXs]) / p.valve_time_constant;
    const ValveFlows q = valve_flows(y[kXs], y[kP1], y[kP2], p.valve_flow_gain, p.supply_pressure, p.laminar_pressure);
    const double q_leak = p.leakage ? (y[kP1] - y[kP2]) / p.leakage_resistance : 0.0;
    const double v1 = std::max(p.dead_volume_cap + p.area_cap * (y[kXr] - p.stroke_min), kMinVolume);
    const double v2 = std::max(p.dead_volume_rod + p.area_rod * (p.stroke_max - y[kXr]), kMinVolume);
    double dp1 = p.bulk_modulus / v1 * (q.q1 - p.area_cap * y[kVr] - q_leak);
    double dp2 = p.bulk_modulus / v2 * (p.area_rod * y[kVr] + q_leak - q.q2);
    if (y[kP1] <= p.cavitation_pressure && dp1 < 0.0) dp1 = 0.0;
    if (y[kP2] <= p.cavitation_pressure && dp2 < 0.0) dp2 = 0.0;
    dy[kP1] = dp1;
    dy[kP2] = dp2;
    const double f_tyre = f0 + p.tyre_stiffness * (y[kXr] - y[kXw]) + p.tyre_damping * (y[kVr] - y[kVw]);
    const double fs = f_susp(y);
    dy[kXr] = y[kVr];
    dy[kVr] = (y[kP1] * p.area_cap - y[kP2] * p.area_rod - p.rod_damping * y[kVr] - f_tyre - p.mass_rod * p.gravity +
               end_stop(y[kXr], y[kVr])) /
              p.mass_rod;
    dy[kXw] = y[kVw];
    dy[kVw] = (f_tyre - f0 - fs) / p.mass_wheel;
    if (!p.bearing_friction.enabled) {
      dy[kXb] = y[kVb];
      dy[kVb] = fs / p.mass_body;
    } else if (mode == BearingMode::kStuck) {
      dy[kXb] = 0.0;
      dy[kVb] = 0.0;
    } else {
      const double fb = sliding_friction(p.bearing_friction, levels(y), direction(mode), y[kVb]);
      dy[kXb] = y[kVb];
      dy[kVb] = (fs - fb) / p.mass_body;
    }
  }

  double event(const Vec& y, double) const {
    if (!p.bearing_friction.enabled) return kNoEvent;
    if (mode == BearingMode::kStuck) return levels(y).breakaway - std::abs(f_susp(y));
    return direction(mode) * y[qc::kVb];
  }

  BearingMode mode_at_rest(const Vec& y) const {
    const double fs = f_susp(y);
    return std::abs(fs) > levels(y).breakaway ? sliding(fs) : BearingMode::kStuck;
  }

  void on_event(Vec& y, double) {
    if (mode == BearingMode::kStuck) {
      mode = sliding(f_susp(y));
      return;
    }
    y[qc::kVb] = 0.0;
    mode = mode_at_rest(y);
  }

  bool post_step(Vec& y) const {
    bool changed = false;
    for (std::size_t i : {qc::kP1, qc::kP2}) {
      if (y[i] < p.cavitation_pressure) {
        y[i] = p.cavitation_pressure;
        changed = true;
      }
    }
    return changed;
  }
};

QuarterCarModel::Vec to_vec(const QuarterCarState& s) {
  return {s.x_s, s.p1, s.p2, s.x_r, s.v_r, s.x_w, s.v_w, s.x_b, s.v_b};
}

// ---------------------------------------------------------------------------
// Pneumatic rotary servo (plant/pneumatic_rotary_plant.cpp).

namespace pr {
constexpr std::size_t kTheta = 0, kOmega = 1, kPa = 2, kPb = 3;
}  // namespace pr

struct PneumaticModel {
  using Vec = std::array<double, 4>;

  explicit PneumaticModel(const PneumaticRotaryParams& params) : p(params), plant(params) {
    levels = plant.hysteresis_levels();
    brake = plant.brake_level();
    holding = levels.step + brake;
    stick_slip = p.hysteresis.enabled || p.brake.enabled;
    gas_gain = p.heat_capacity_ratio * p.gas_constant * p.supply_temperature / p.chamber_volume;
    motion_gain = p.heat_capacity_ratio * p.quiescent_pressure * p.first_moment / p.chamber_volume;
  }

  PneumaticRotaryParams p;
  PneumaticRotaryPlant plant;  // for spool_position() and the derived levels only
  BladderHysteresisLevels levels;
  double brake = 0.0, holding = 0.0, gas_gain = 0.0, motion_gain = 0.0;
  bool stick_slip = false;
  RotaryLoadMode mode = RotaryLoadMode::kStuck;
  HysteresisAnchor anchor;
  double u = 0.0;

  static int direction(RotaryLoadMode m) {
    return m == RotaryLoadMode::kSlidingPositive ? 1 : (m == RotaryLoadMode::kSlidingNegative ? -1 : 0);
  }
  static RotaryLoadMode mode_for(int d) {
    return d > 0 ? RotaryLoadMode::kSlidingPositive : (d < 0 ? RotaryLoadMode::kSlidingNegative : RotaryLoadMode::kStuck);
  }

  void set_command(const HeldCommand& c, Vec&) { u = std::isfinite(c[0]) ? c[0] : 0.0; }

  double end_stop(double theta, double omega) const {
    if (theta > p.angle_limit) return std::min(0.0, -p.end_stop_stiffness * (theta - p.angle_limit) - p.end_stop_damping * omega);
    if (theta < -p.angle_limit) return std::max(0.0, -p.end_stop_stiffness * (theta + p.angle_limit) - p.end_stop_damping * omega);
    return 0.0;
  }
  double elastic(double theta) const { return bladder_elastic_torque(levels, anchor, theta); }
  double residual(const Vec& y) const {
    return p.first_moment * (y[pr::kPa] - y[pr::kPb]) + end_stop(y[pr::kTheta], y[pr::kOmega]) - elastic(y[pr::kTheta]);
  }

  void rhs(const Vec& y, Vec& dy, double t) const {
    using namespace pr;
    const bool stuck = stick_slip && mode == RotaryLoadMode::kStuck;
    const double omega = stuck ? 0.0 : y[kOmega];
    const double x = plant.spool_position(u, t);
    const double m_a = p.flow_gain * x - p.flow_pressure_coefficient * y[kPa];
    const double m_b = -p.flow_gain * x - p.flow_pressure_coefficient * y[kPb];
    dy[kPa] = gas_gain * m_a - motion_gain * omega;
    dy[kPb] = gas_gain * m_b + motion_gain * omega;
    if (stuck) {
      dy[kTheta] = 0.0;
      dy[kOmega] = 0.0;
      return;
    }
    const double friction = stick_slip ? direction(mode) * holding : 0.0;
    dy[kTheta] = omega;
    dy[kOmega] = (residual(y) - friction) / p.inertia;
  }

  double event(const Vec& y, double) const {
    if (!stick_slip) return kNoEvent;
    if (mode == RotaryLoadMode::kStuck) return holding - std::abs(residual(y));
    return direction(mode) * y[pr::kOmega];
  }

  void enter(RotaryLoadMode m, const Vec& y) {
    anchor = {y[pr::kTheta], elastic(y[pr::kTheta])};
    mode = m;
  }

  void on_event(Vec& y, double) {
    if (mode == RotaryLoadMode::kStuck) {
      enter(mode_for(breakaway_direction(residual(y), holding)), y);
      return;
    }
    y[pr::kOmega] = 0.0;
    enter(mode_for(breakaway_direction(residual(y), holding)), y);
  }

  bool post_step(Vec&) const { return false; }
};

// ---------------------------------------------------------------------------
// Half car (plant/half_car_plant.cpp).

namespace hc {
constexpr std::size_t kZs = 0, kPhi = 1, kZu1 = 2, kZu2 = 3, kVs = 4, kOmega = 5, kVu1 = 6, kVu2 = 7, kF1 = 8, kF2 = 9;
}  // namespace hc

struct HalfCarModel {
  using Vec = std::array<double, 10>;

  explicit HalfCarModel(const HalfCarParams& params) : p(params), plant(params) {
    const double kt[2] = {p.tyre_stiffness_1, p.tyre_stiffness_2};
    for (int i = 0; i < 2; ++i) {
      lever[i] = plant.lever_arm(i);
      static_load[i] = plant.static_tyre_load(i);
      free_compression[i] = static_load[i] / kt[i];
    }
  }

  HalfCarParams p;
  HalfCarPlant plant;  // road, lever arms, static loads and roll moment
  double lever[2] = {0, 0}, static_load[2] = {0, 0}, free_compression[2] = {0, 0};
  double u[2] = {0, 0};

  void set_command(const HeldCommand& c, Vec& y) {
    for (std::size_t i = 0; i < 2; ++i) {
      double v = std::isfinite(c[i]) ? c[i] : 0.0;
      if (p.actuator_force_limit > 0.0) v = std::clamp(v, -p.actuator_force_limit, p.actuator_force_limit);
      u[i] = v;
      if (p.actuator_time_constant <= 0.0) y[hc::kF1 + i] = v;
    }
  }

  double tyre(const Vec& y, int wheel, double t) const {
    const auto k = static_cast<std::size_t>(wheel);
    const RoadSample r = plant.road().at(wheel, t);
    const double zu = y[hc::kZu1 + k];
    if (free_compression[k] + r.z - zu <= 0.0) return 0.0;
    const double kt = wheel == 0 ? p.tyre_stiffness_1 : p.tyre_stiffness_2;
    const double ct = wheel == 0 ? p.tyre_damping_1 : p.tyre_damping_2;
    return std::max(0.0, static_load[k] + kt * (r.z - zu) + ct * (r.dz - y[hc::kVu1 + k]));
  }

  void rhs(const Vec& y, Vec& dy, double t) const {
    using namespace hc;
    const double k[2] = {p.spring_1, p.spring_2};
    const double c[2] = {p.damper_1, p.damper_2};
    const double mu[2] = {p.mass_unsprung_1, p.mass_unsprung_2};
    double heave = 0.0;
    double moment = plant.roll_moment(t);
    for (std::size_t i = 0; i < 2; ++i) {
      const double l = lever[i];
      const double travel = y[kZs] + l * y[kPhi] - y[kZu1 + i];
      const double rate = y[kVs] + l * y[kOmega] - y[kVu1 + i];
      const double damping = rate > 0.0 ? c[i] * p.damper_rebound_factor : c[i];
      const double f_body = -k[i] * travel - damping * rate + y[kF1 + i];
      heave += f_body;
      moment += l * f_body;
      const double tyre_change = tyre(y, static_cast<int>(i), t) - static_load[i];
      dy[kZu1 + i] = y[kVu1 + i];
      dy[kVu1 + i] = (tyre_change - f_body) / mu[i];
    }
    dy[kZs] = y[kVs];
    dy[kPhi] = y[kOmega];
    dy[kVs] = heave / p.mass_body;
    dy[kOmega] = moment / p.inertia_body;
    if (p.actuator_time_constant > 0.0) {
      dy[kF1] = (u[0] - y[kF1]) / p.actuator_time_constant;
      dy[kF2] = (u[1] - y[kF2]) / p.actuator_time_constant;
    } else {
      dy[kF1] = dy[kF2] = 0.0;
    }
  }

  double event(const Vec&, double) const { return kNoEvent; }
  void on_event(Vec&, double) {}
  bool post_step(Vec&) const { return false; }
};

HalfCarModel::Vec to_vec(const HalfCarState& s) {
  return {s.z_s, s.phi, s.z_u1, s.z_u2, s.v_s, s.omega, s.v_u1, s.v_u2, s.f_act1, s.f_act2};
}

template <class Vec>
std::vector<double> as_vector(const Vec& y) {
  return std::vector<double>(y.begin(), y.end());
}

}  // namespace

// ---------------------------------------------------------------------------

std::vector<std::string> quarter_car_state_names() { return {"x_s", "p1", "p2", "x_r", "v_r", "x_w", "v_w", "x_b", "v_b"}; }
std::vector<double> state_vector(const QuarterCarState& s) { return as_vector(to_vec(s)); }
std::vector<std::string> pneumatic_state_names() { return {"theta", "omega", "p_a", "p_b"}; }
std::vector<double> state_vector(const PneumaticRotaryState& s) { return {s.theta, s.omega, s.p_a, s.p_b}; }
std::vector<std::string> half_car_state_names() {
  return {"z_s", "phi", "z_u1", "z_u2", "v_s", "omega", "v_u1", "v_u2", "f_act1", "f_act2"};
}
std::vector<double> state_vector(const HalfCarState& s) { return as_vector(to_vec(s)); }

ReferenceResult reference_quarter_car(const QuarterCarParams& p, const CommandSeries& u, double period_s,
                                      double tolerance, const std::atomic<bool>& stop) {
  QuarterCarModel model(p);
  const QuarterCarState rest = QuarterCarPlant::rest_state(p);
  model.mode = rest.bearing;
  auto r = run_reference(model, to_vec(rest), u, period_s, tolerance, stop,
                         [](const QuarterCarModel::Vec& y) { return as_vector(y); });
  r.names = quarter_car_state_names();
  return r;
}

ReferenceResult reference_pneumatic(const PneumaticRotaryParams& p, const CommandSeries& u, double period_s,
                                    double tolerance, const std::atomic<bool>& stop) {
  PneumaticModel model(p);
  model.mode = RotaryLoadMode::kStuck;
  model.anchor = {};
  auto r = run_reference(model, PneumaticModel::Vec{0.0, 0.0, 0.0, 0.0}, u, period_s, tolerance, stop,
                         [](const PneumaticModel::Vec& y) { return as_vector(y); });
  r.names = pneumatic_state_names();
  return r;
}

ReferenceResult reference_half_car(const HalfCarParams& p, const CommandSeries& u, double period_s,
                                   double tolerance, const std::atomic<bool>& stop) {
  HalfCarModel model(p);
  auto r = run_reference(model, HalfCarModel::Vec{}, u, period_s, tolerance, stop,
                         [](const HalfCarModel::Vec& y) { return as_vector(y); });
  r.names = half_car_state_names();
  return r;
}

double rhs_agreement_quarter_car(const QuarterCarParams& p, const std::vector<QuarterCarState>& states,
                                 const std::vector<HeldCommand>& u, double h, int& checked) {
  QuarterCarParams one = p;
  one.substeps = 1;
  QuarterCarPlant plant(one);
  QuarterCarModel model(p);
  double worst = 0.0;
  checked = 0;
  for (std::size_t i = 0; i < states.size() && i < u.size(); ++i) {
    plant.set_state(states[i]);
    const QuarterCarState before = plant.state();
    const std::array<double, 1> cmd{u[i][0]};
    plant.advance(cmd, h);
    const QuarterCarState after = plant.state();
    if (after.bearing != before.bearing) continue;
    model.mode = before.bearing;
    QuarterCarModel::Vec y = to_vec(before);
    model.set_command(u[i], y);
    const auto ours = rk4_step(model, y, 0.0, h);
    worst = std::max(worst, step_difference(to_vec(before), ours, state_vector(after)));
    ++checked;
  }
  return worst;
}

double rhs_agreement_pneumatic(const PneumaticRotaryParams& p, const std::vector<PneumaticRotaryState>& states,
                               const std::vector<HeldCommand>& u, double h, int& checked) {
  PneumaticRotaryParams one = p;
  one.substeps = 1;
  PneumaticRotaryPlant plant(one);
  PneumaticModel model(p);
  double worst = 0.0;
  checked = 0;
  for (std::size_t i = 0; i < states.size() && i < u.size(); ++i) {
    plant.set_state(states[i]);
    const PneumaticRotaryState before = plant.state();
    const std::array<double, 1> cmd{u[i][0]};
    plant.advance(cmd, h);
    const PneumaticRotaryState after = plant.state();
    if (model.stick_slip && after.mode != before.mode) continue;
    model.mode = before.mode;
    model.anchor = before.anchor;
    PneumaticModel::Vec y{before.theta, before.omega, before.p_a, before.p_b};
    model.set_command(u[i], y);
    const auto ours = rk4_step(model, y, before.time, h);
    worst = std::max(worst, step_difference(y, ours, state_vector(after)));
    ++checked;
  }
  return worst;
}

double rhs_agreement_half_car(const HalfCarParams& p, const std::vector<HalfCarState>& states,
                              const std::vector<HeldCommand>& u, double h, int& checked) {
  HalfCarParams one = p;
  one.substeps = 1;
  HalfCarPlant plant(one);
  HalfCarModel model(p);
  double worst = 0.0;
  checked = 0;
  for (std::size_t i = 0; i < states.size() && i < u.size(); ++i) {
    plant.set_state(states[i]);
    const HalfCarState before = plant.state();
    const std::array<double, 2> cmd{u[i][0], u[i][1]};
    plant.advance(cmd, h);
    HalfCarModel::Vec y = to_vec(before);
    model.set_command(u[i], y);
    HalfCarModel::Vec start = y;
    const auto ours = rk4_step(model, y, before.time, h);
    worst = std::max(worst, step_difference(start, ours, state_vector(plant.state())));
    ++checked;
  }
  return worst;
}

}  // namespace rigctl::bench
