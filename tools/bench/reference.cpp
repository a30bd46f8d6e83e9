// Reference solutions of the plants with Boost.Odeint (see tools/bench/reference.hpp).
#include "tools/bench/reference.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <boost/numeric/odeint.hpp>

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

// The models below adapt each plant's own continuous model (its public
// derivatives() and stick/slip pieces) to the integrator's interface: the
// equations are the plant's; what is here is the event handling, which the
// plants do at sub-step ends and the reference locates exactly.

// ---------------------------------------------------------------------------
// Quarter car: bearing stick/slip events.

struct QuarterCarModel {
  using Vec = QuarterCarPlant::Vec;

  explicit QuarterCarModel(const QuarterCarParams& params) : plant(params) {}

  QuarterCarPlant plant;
  BearingMode mode = BearingMode::kStuck;
  double u = 0.0;

  bool friction() const { return plant.params().bearing_friction.enabled; }
  void set_command(const HeldCommand& c, Vec&) { u = QuarterCarPlant::held_command(c[0]); }
  void rhs(const Vec& y, Vec& dy, double) const { plant.derivatives(y, mode, u, dy); }

  double event(const Vec& y, double) const {
    if (!friction()) return kNoEvent;
    if (mode == BearingMode::kStuck) return plant.levels_at(y).breakaway - std::abs(plant.suspension_force(y));
    return slide_direction(mode) * y[QuarterCarPlant::kVbIndex];
  }
  void on_event(Vec& y, double) {
    if (mode == BearingMode::kStuck) {
      mode = sliding_mode(plant.suspension_force(y));
      return;
    }
    y[QuarterCarPlant::kVbIndex] = 0.0;
    mode = plant.mode_at_rest(y);
  }
  bool post_step(Vec& y) const {
    const Vec before = y;
    plant.apply_floors(y);
    return y != before;
  }
};

// ---------------------------------------------------------------------------
// Pneumatic rotary servo: load stick/slip events, each re-anchoring the
// bladder hysteresis (held in the plant instance).

struct PneumaticModel {
  using Vec = PneumaticRotaryPlant::Vec;

  explicit PneumaticModel(const PneumaticRotaryParams& params) : plant(params) {}

  PneumaticRotaryPlant plant;
  RotaryLoadMode mode = RotaryLoadMode::kStuck;
  double u = 0.0;

  void set_command(const HeldCommand& c, Vec&) { u = PneumaticRotaryPlant::held_command(c[0]); }
  void rhs(const Vec& y, Vec& dy, double t) const { plant.derivatives(y, t, mode, u, dy); }

  double event(const Vec& y, double) const {
    if (!plant.stick_slip()) return kNoEvent;
    if (mode == RotaryLoadMode::kStuck) return plant.holding_torque() - std::abs(plant.residual_torque(y));
    return slide_direction(mode) * y[PneumaticRotaryPlant::kOmegaIndex];
  }
  void on_event(Vec& y, double) {
    if (mode != RotaryLoadMode::kStuck) y[PneumaticRotaryPlant::kOmegaIndex] = 0.0;
    mode = plant.mode_at_rest(y);
    plant.enter_mode_at(mode, y[0]);
  }
  bool post_step(Vec&) const { return false; }
};

// ---------------------------------------------------------------------------
// Half car: no events (the tyre's contact is a continuous max()).

struct HalfCarModel {
  using Vec = HalfCarPlant::Vec;

  explicit HalfCarModel(const HalfCarParams& params) : plant(params) {}

  HalfCarPlant plant;
  HalfCarPlant::Command2 u{};

  void set_command(const HeldCommand& c, Vec& y) {
    u = plant.held_command(c);
    plant.hold_command(u, y);
  }
  void rhs(const Vec& y, Vec& dy, double t) const { plant.derivatives(y, t, u, dy); }
  double event(const Vec&, double) const { return kNoEvent; }
  void on_event(Vec&, double) {}
  bool post_step(Vec&) const { return false; }
};

template <class Vec>
std::vector<double> as_vector(const Vec& y) {
  return std::vector<double>(y.begin(), y.end());
}

}  // namespace

// ---------------------------------------------------------------------------

std::vector<std::string> quarter_car_state_names() { return {"x_s", "p1", "p2", "x_r", "v_r", "x_w", "v_w", "x_b", "v_b"}; }
std::vector<double> state_vector(const QuarterCarState& s) { return as_vector(QuarterCarPlant::to_vec(s)); }
std::vector<std::string> pneumatic_state_names() { return {"theta", "omega", "p_a", "p_b"}; }
std::vector<double> state_vector(const PneumaticRotaryState& s) { return {s.theta, s.omega, s.p_a, s.p_b}; }
std::vector<std::string> half_car_state_names() {
  return {"z_s", "phi", "z_u1", "z_u2", "v_s", "omega", "v_u1", "v_u2", "f_act1", "f_act2", "f_valve1", "f_valve2"};
}
std::vector<double> state_vector(const HalfCarState& s) { return as_vector(HalfCarPlant::to_vec(s)); }

ReferenceResult reference_quarter_car(const QuarterCarParams& p, const CommandSeries& u, double period_s,
                                      double tolerance, const std::atomic<bool>& stop) {
  QuarterCarModel model(p);
  const QuarterCarState rest = QuarterCarPlant::rest_state(p);
  model.mode = rest.bearing;
  auto r = run_reference(model, QuarterCarPlant::to_vec(rest), u, period_s, tolerance, stop,
                         [](const QuarterCarModel::Vec& y) { return as_vector(y); });
  r.names = quarter_car_state_names();
  return r;
}

ReferenceResult reference_pneumatic(const PneumaticRotaryParams& p, const CommandSeries& u, double period_s,
                                    double tolerance, const std::atomic<bool>& stop) {
  PneumaticModel model(p);
  model.mode = RotaryLoadMode::kStuck;  // as reset(): at rest, hysteresis unloaded
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
    QuarterCarModel::Vec y = QuarterCarPlant::to_vec(before);
    model.set_command(u[i], y);
    const auto ours = rk4_step(model, y, 0.0, h);
    worst = std::max(worst, step_difference(QuarterCarPlant::to_vec(before), ours, state_vector(after)));
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
    if (model.plant.stick_slip() && after.mode != before.mode) continue;
    model.mode = before.mode;
    model.plant.set_state(before);  // its hysteresis anchor
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
    HalfCarModel::Vec y = HalfCarPlant::to_vec(before);
    model.set_command(u[i], y);
    HalfCarModel::Vec start = y;
    const auto ours = rk4_step(model, y, before.time, h);
    worst = std::max(worst, step_difference(start, ours, state_vector(plant.state())));
    ++checked;
  }
  return worst;
}

}  // namespace rigctl::bench
