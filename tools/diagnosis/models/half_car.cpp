// Diagnosis sub-model of the half car (seed 001, docs/rig-models.md 3):
// open-loop replay of the measured roads z_r1, z_r2 and the actuator force
// commands f_1, f_2 through the linear 4-DOF model of plant/half_car/half_car_model.hpp
// (centre-of-gravity coordinates), outputs z_s, phi, z_u1, z_u2.
//
// Replay conventions (what the recorded run holds, checked on a run of
// `rigctl run config/half_car.yaml --csv`): row k's f_1, f_2 are the forces
// the controller COMMANDED at t_k (the telemetry's command record; the force
// acting in the plant is a simulator truth channel and never reaches a run
// file). The driver holds that command over [t_k, t_k+1) (zero-order hold,
// as a DAC does), so the replay holds f_k over the period too, and an
// actuator that does not follow its command shows up as actuator_lag. The
// roads are displacement transducers sampled at t_k: linear between samples
// (the road under a wheel is continuous). Absent f columns: passive (0).
//
// Baseline: the nominal linear model with the two suspension dampers free
// (the least certain of the catalogue values, and the term damper_asymmetry
// must not be confused with a plain damping error). Candidates, one per
// cause id of the contract, each null at 0:
//   actuator_lag      F acting = first-order lag tau_a of the command, exact
//                     under the held command (not the plant's formula: the
//                     generator's actuator is second order, integrated at
//                     its sub-steps)
//   tyre_liftoff      tyre force (1 - w) F + w softplus(F) with F the linear
//                     total tyre force (static load included): w = 1 cannot
//                     pull, smoothed over 2 % of the static load (the plant's
//                     tyre is sharp)
//   damper_asymmetry  F_d = c_i (1 + a tanh(v / 0.01 m/s)) v: rebound c(1 + a),
//                     compression c(1 - a) (the plant switches sharply)
//   sensor_delay      each output through a sensor of its own group delay, in
//                     the form that fits best (sensor_filter.hpp)
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include "config/rig_config.hpp"
#include "plant/half_car/half_car_params.hpp"
#include "tools/diagnosis/rigs.hpp"
#include "tools/diagnosis/sensor_filter.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {

namespace {

// Smooth max(0, x) over a band eps, overflow-safe.
double softplus(double x, double eps) {
  const double z = x / eps;
  if (z > 40.0) return x;  // exp(-40) = 4e-18: x to double precision (the common case: tyre loaded)
  return z > 0.0 ? x + eps * std::log1p(std::exp(-z)) : eps * std::log1p(std::exp(z));
}

constexpr double kRateBand = 0.01;      // [m/s] tanh band of the asymmetric damper (as quarter_car's)
constexpr double kTyreBand = 0.02;      // softplus band of the tyre, share of the static load
constexpr int kSubsteps = 2;            // RK4 at 1.25 ms: wheel hop (~10 Hz) at omega h = 0.08

class HalfCarDiagModel : public RigModel {
 public:
  HalfCarDiagModel(const RunFile& run, const RigModelOptions& o) {
    p_ = load_params(o.config_path);
    const int dec = std::max(1, o.decimate);
    decimate_ = dec;
    const bool has_f = run.has("f_1") && run.has("f_2");
    if (run.has("f_1") != run.has("f_2"))
      throw RunFileError("half_car: f_1 and f_2 come together (both columns or neither)");
    active_ = has_f;
    const char* names[4] = {"z_s", "phi", "z_u1", "z_u2"};
    std::vector<std::vector<double>> meas(4);
    const std::size_t step = static_cast<std::size_t>(dec);
    for (std::size_t i = 0; i < run.size(); i += step) {
      t_.push_back(run.t[i]);
      zr_[0].push_back(run.col("z_r1")[i]);
      zr_[1].push_back(run.col("z_r2")[i]);
      // A held command over a decimated period: the mean of the commands held in it.
      for (std::size_t w = 0; w < 2; ++w) {
        double sum = 0.0;
        const std::size_t end = std::min(run.size(), i + step);
        if (has_f)
          for (std::size_t j = i; j < end; ++j) sum += run.col(w == 0 ? "f_1" : "f_2")[j];
        f_[w].push_back(sum / static_cast<double>(end - i));
      }
      for (std::size_t c = 0; c < 4; ++c) meas[c].push_back(run.col(names[c])[i]);
    }
    dt_ = run.dt * dec;
    for (std::size_t c = 0; c < 4; ++c) outputs_.push_back({names[c], meas[c]});
    lever_[0] = half_car_lever_arm(p_, 0);
    lever_[1] = half_car_lever_arm(p_, 1);
    static_load_[0] = half_car_static_tyre_load(p_, 0);
    static_load_[1] = half_car_static_tyre_load(p_, 1);
    m_roll_full_ = half_car_roll_moment(p_);
    // Initial state: a least-squares line through the first samples (position
    // and slope), so that sensor noise does not set a velocity.
    const std::size_t m = std::min<std::size_t>(8, t_.size());
    for (std::size_t c = 0; c < 4; ++c) {
      double st = 0, sy = 0, stt = 0, sty = 0;
      for (std::size_t i = 0; i < m; ++i) {
        const double tt = static_cast<double>(i) * dt_, y = meas[c][i];
        st += tt, sy += y, stt += tt * tt, sty += tt * y;
      }
      const double den = static_cast<double>(m) * stt - st * st;
      const double slope = den > 0 ? (static_cast<double>(m) * sty - st * sy) / den : 0.0;
      x0_[c] = (sy - slope * st) / static_cast<double>(m);
      v0_[c] = slope;
    }
    // Indicators from the measured signals.
    rate1_.resize(t_.size());
    for (std::size_t i = 0; i < t_.size(); ++i) rate1_[i] = meas[0][i] + lever_[0] * meas[1][i] - meas[2][i];
    rate1_ = central_diff(rate1_, dt_);
    vu1_ = central_diff(meas[2], dt_);
    df1_ = central_diff(f_[0], dt_);
    load_.resize(t_.size());
    const double kt[2] = {p_.tyre_stiffness_1, p_.tyre_stiffness_2};
    for (std::size_t i = 0; i < t_.size(); ++i) {
      double lo = 1e9;
      for (std::size_t w = 0; w < 2; ++w)
        lo = std::min(lo, (static_load_[w] + kt[w] * (zr_[w][i] - meas[2 + w][i])) / static_load_[w]);
      load_[i] = lo;
    }
  }

  RunFileRig rig() const override { return RunFileRig::kHalfCar; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }
  std::vector<ParamSpec> baseline() const override {
    // The two dampers (the least certain catalogue values, 10 %) and every
    // other value of the vehicle with a prior of 5 %: a car on a rig is never
    // its data sheet (load, tyre pressure, bushings).
    const auto& p = p_;
    return {Prior("c_1", "N s/m", p.damper_1, 0.10),        Prior("c_2", "N s/m", p.damper_2, 0.10),
            Prior("k_1", "N/m", p.spring_1, 0.05),          Prior("k_2", "N/m", p.spring_2, 0.05),
            Prior("kt_1", "N/m", p.tyre_stiffness_1, 0.05), Prior("kt_2", "N/m", p.tyre_stiffness_2, 0.05),
            Prior("m_s", "kg", p.mass_body, 0.05),          Prior("I", "kg m^2", p.inertia_body, 0.05),
            Prior("m_u1", "kg", p.mass_unsprung_1, 0.05),   Prior("m_u2", "kg", p.mass_unsprung_2, 0.05),
            Prior("l_1", "m", std::abs(lever_[0]), 0.05),   Prior("l_2", "m", std::abs(lever_[1]), 0.05)};
  }
  std::vector<EffectSpec> effects() const override {
    // Start grids: the lag and the delay are non-convex scalars; a second start
    // a few times larger covers strong effects (docs/diagnosis.md 4).
    return {
        {"actuator_lag", {P("tau_a", "s", 0.005, 0.0, 0.2, 0.01, 0.0, true, {0.025})},
         "the active force follows its command through a first-order lag tau_a"},
        {"tyre_liftoff", {P("unilateral", "1", 0.5, 0.0, 1.0, 1.0, 0.0, true)},
         "the tyre cannot pull: contact force softplus(F) blended by `unilateral` (1: leaves the ground)"},
        {"damper_asymmetry", {P("asym", "1", 0.0, -0.95, 0.95, 0.1, 0.0, true)},
         "rebound and compression damping differ: c (1 + asym tanh(v_rel / 0.01 m/s)), i.e. "
         "c_reb / c_comp = (1 + asym) / (1 - asym)"},
        {"sensor_delay",
         {OnChannel(P("tau_z_s", "s", 0.002, 0.0, 0.05, 0.002, 0.0, true, {0.008}), "z_s"),
          OnChannel(P("tau_phi", "s", 0.002, 0.0, 0.05, 0.002, 0.0, true), "phi"),
          OnChannel(P("tau_z_u1", "s", 0.002, 0.0, 0.05, 0.002, 0.0, true, {0.008}), "z_u1"),
          OnChannel(P("tau_z_u2", "s", 0.002, 0.0, 0.05, 0.002, 0.0, true), "z_u2"), FormIndex()},
         "z_s, phi, z_u1, z_u2 each measured through a sensor of its own group delay tau, in the form that fits "
         "best: a pure delay, a first-order lag or a Bessel or Butterworth filter of order 2-4",
         sensor_form_names()},
    };
  }
  std::string replay() const override {
    return std::string("open-loop replay of the 4-DOF half car: measured z_r1, z_r2 (linear between samples) and ") +
           (active_ ? "commanded actuator forces f_1, f_2 (held over each period, as the DAC does)"
                    : "no actuator forces (passive: no f_1, f_2 columns)") +
           " drive the linear model; RK4, " + std::to_string(kSubsteps) + " sub-steps per " +
           std::to_string(static_cast<int>(std::lround(dt_ * 1e6))) + " us sample" +
           (decimate_ > 1 ? " (decimated by " + std::to_string(decimate_) + ")" : "");
  }

  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    run(th, y, kNoPlace, nullptr);
  }
  // Where an effect can enter (docs/diagnosis.md 3); the order is run()'s
  // `place`. The sensors' errors the engine adds after the replay.
  std::vector<Place> places() const override {
    return {{"a heave force on the body", "N", 1.0, -1, false, {}},
            {"a pitch moment on the body", "N m", 1.0, -1, false, {}},
            {"a force between body and wheel 1 (suspension and actuator 1)", "N", 1.0, -1, false,
             {"actuator_lag", "damper_asymmetry"}},
            {"a force between body and wheel 2 (suspension and actuator 2)", "N", 1.0, -1, false,
             {"actuator_lag", "damper_asymmetry"}},
            {"a force on wheel 1 (its tyre)", "N", 1.0, -1, false, {"tyre_liftoff"}},
            {"a force on wheel 2 (its tyre)", "N", 1.0, -1, false, {"tyre_liftoff"}},
            {"an error on the z_s sensor", "m", 1e-5, 0, false, {"sensor_delay"}},
            {"an error on the phi sensor", "rad", 1e-5, 1, false, {"sensor_delay"}},
            {"an error on the z_u1 sensor", "m", 1e-5, 2, false, {"sensor_delay"}},
            {"an error on the z_u2 sensor", "m", 1e-5, 3, false, {"sensor_delay"}}};
  }
  std::vector<Feature> features() const override {
    std::vector<Feature> f;
    const double kt[2] = {p_.tyre_stiffness_1, p_.tyre_stiffness_2};
    for (std::size_t w = 0; w < 2; ++w) {
      const std::string c = std::to_string(w + 1);
      std::vector<double> rate(t_.size()), load(t_.size());
      for (std::size_t i = 0; i < t_.size(); ++i) {
        rate[i] = outputs_[0].measured[i] + lever_[w] * outputs_[1].measured[i] - outputs_[2 + w].measured[i];
        load[i] = static_load_[w] + kt[w] * (zr_[w][i] - outputs_[2 + w].measured[i]);
      }
      const int wheel = static_cast<int>(2 + w);  // outputs: z_s 0, phi 1, z_u1 2, z_u2 3
      f.push_back({"suspension rate " + c, FeatureKind::kVelocity, central_diff(rate, dt_), {0, 1, wheel}});
      f.push_back({"v_u" + c, FeatureKind::kVelocity, central_diff(outputs_[2 + w].measured, dt_), {wheel}});
      f.push_back({"tyre load " + c, FeatureKind::kValue, load, {wheel}});
      if (active_) {
        f.push_back({"f_" + c, FeatureKind::kValue, f_[w]});
        f.push_back({"df_" + c + "/dt", FeatureKind::kValue, central_diff(f_[w], dt_)});
      }
    }
    return f;
  }
  void simulate_with_input(const std::vector<double>& th, std::size_t place, const std::vector<double>& d,
                           std::vector<std::vector<double>>& y) const override {
    run(th, y, place, &d);
  }

  Indicator indicator(const std::string& cause) const override {
    if (cause == "actuator_lag") return {"df_1/dt, commanded [N/s]", df1_};
    if (cause == "tyre_liftoff") return {"lower tyre load / static load (from measured z_r - z_u)", load_};
    if (cause == "damper_asymmetry") return {"corner-1 suspension rate [m/s] (from measured)", rate1_};
    if (cause == "sensor_delay") return {"dz_u1/dt [m/s]", vu1_};
    return {};
  }

 private:
  static constexpr std::size_t kNoPlace = static_cast<std::size_t>(-1);
  // The replay; d: the where's signal at places()[place] (null: none).
  void run(const std::vector<double>& th, std::vector<std::vector<double>>& y, std::size_t place,
           const std::vector<double>* added) const {
    // What the where adds over sample i: heave, pitch, corner and wheel forces.
    double e_heave = 0.0, e_pitch = 0.0, e_corner[2] = {0.0, 0.0}, e_wheel[2] = {0.0, 0.0};
    auto set_added = [&](std::size_t i) {
      if (!added) return;
      const double v = (*added)[i];
      e_heave = place == 0 ? v : 0.0;
      e_pitch = place == 1 ? v : 0.0;
      e_corner[0] = place == 2 ? v : 0.0, e_corner[1] = place == 3 ? v : 0.0;
      e_wheel[0] = place == 4 ? v : 0.0, e_wheel[1] = place == 5 ? v : 0.0;
    };
    const double c[2] = {th[0], th[1]};
    const double k[2] = {th[2], th[3]};
    const double kt[2] = {th[4], th[5]};
    const double ms = th[6], inertia = th[7];
    const double mu[2] = {th[8], th[9]};
    const double lever[2] = {th[10], -th[11]};
    const double tau_a = th[12], uni = th[13], asym = th[14];
    const std::size_t n = t_.size();
    y.assign(4, std::vector<double>(n, 0.0));
    const double ct[2] = {p_.tyre_damping_1, p_.tyre_damping_2};
    // Static tyre loads of these masses and lever arms (the body's weight
    // shared by the arms, as half_car_static_tyre_load).
    const double static_load[2] = {mu[0] * p_.gravity + ms * p_.gravity * (-lever[1]) / (lever[0] - lever[1]),
                                   mu[1] * p_.gravity + ms * p_.gravity * lever[0] / (lever[0] - lever[1])};
    const double eps[2] = {kTyreBand * static_load[0], kTyreBand * static_load[1]};
    const double h = dt_ / kSubsteps;
    const double decay_h = tau_a > 1e-6 ? std::exp(-0.5 * h / tau_a) : 0.0;  // lag over half a sub-step
    // q = [z_s, phi, z_u1, z_u2, v_s, omega, v_u1, v_u2]
    std::array<double, 8> q{x0_[0], x0_[1], x0_[2], x0_[3], v0_[0], v0_[1], v0_[2], v0_[3]};
    double fa[2] = {f_[0][0], f_[1][0]};  // force acting (lag state)
    auto deriv = [&](const std::array<double, 8>& s, const double zr[2], const double vr[2], const double fact[2],
                     double m_roll, std::array<double, 8>& d) {
      double heave = 0.0, moment = m_roll;
      for (std::size_t w = 0; w < 2; ++w) {
        const double l = lever[w];
        const double travel = s[0] + l * s[1] - s[2 + w];
        const double rate = s[4] + l * s[5] - s[6 + w];
        const double damp = c[w] * (1.0 + (asym != 0.0 ? asym * std::tanh(rate / kRateBand) : 0.0)) * rate;
        const double fb = -k[w] * travel - damp + fact[w] + e_corner[w];
        heave += fb;
        moment += l * fb;
        const double ft = static_load[w] + kt[w] * (zr[w] - s[2 + w]) + ct[w] * (vr[w] - s[6 + w]);
        const double fe = uni > 0.0 ? (1.0 - uni) * ft + uni * softplus(ft, eps[w]) : ft;
        d[2 + w] = s[6 + w];
        d[6 + w] = (fe - static_load[w] - fb + e_wheel[w]) / mu[w];
      }
      d[0] = s[4];
      d[1] = s[5];
      d[4] = (heave + e_heave) / ms;
      d[5] = (moment + e_pitch) / inertia;
    };
    std::array<double, 8> k1, k2, k3, k4, s;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c4 = 0; c4 < 4; ++c4) y[c4][i] = q[c4];
      if (i + 1 == n) break;
      set_added(i);
      double vr[2], zr0[2];
      for (std::size_t w = 0; w < 2; ++w) {
        zr0[w] = zr_[w][i];
        vr[w] = (zr_[w][i + 1] - zr_[w][i]) / dt_;
      }
      const double u[2] = {f_[0][i], f_[1][i]};
      for (int sub = 0; sub < kSubsteps; ++sub) {
        const double t0 = t_[i] + sub * h;
        const double a0 = sub * h;  // time into the period
        double zr_a[2], zr_b[2], zr_c[2], f_a[2], f_b[2], f_c[2];
        for (std::size_t w = 0; w < 2; ++w) {
          zr_a[w] = zr0[w] + vr[w] * a0;
          zr_b[w] = zr0[w] + vr[w] * (a0 + 0.5 * h);
          zr_c[w] = zr0[w] + vr[w] * (a0 + h);
          // Exact first-order lag under the held command at the stage times.
          f_a[w] = fa[w];
          f_b[w] = tau_a > 1e-6 ? u[w] + (fa[w] - u[w]) * decay_h : u[w];
          f_c[w] = tau_a > 1e-6 ? u[w] + (fa[w] - u[w]) * decay_h * decay_h : u[w];
        }
        const double m0 = roll_moment(t0), m1 = roll_moment(t0 + 0.5 * h), m2 = roll_moment(t0 + h);
        deriv(q, zr_a, vr, f_a, m0, k1);
        for (std::size_t j = 0; j < 8; ++j) s[j] = q[j] + 0.5 * h * k1[j];
        deriv(s, zr_b, vr, f_b, m1, k2);
        for (std::size_t j = 0; j < 8; ++j) s[j] = q[j] + 0.5 * h * k2[j];
        deriv(s, zr_b, vr, f_b, m1, k3);
        for (std::size_t j = 0; j < 8; ++j) s[j] = q[j] + h * k3[j];
        deriv(s, zr_c, vr, f_c, m2, k4);
        for (std::size_t j = 0; j < 8; ++j) q[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        for (std::size_t w = 0; w < 2; ++w) fa[w] = f_c[w];
      }
      if (!std::isfinite(q[0]) || !std::isfinite(q[2]) || !std::isfinite(q[3]) || std::abs(q[0]) > 10.0) {
        for (std::size_t j = i + 1; j < n; ++j)
          for (std::size_t c4 = 0; c4 < 4; ++c4) y[c4][j] = 1e3;
        return;
      }
    }
    // The four sensors (sensor_delay): th[15..18] their group delays, th[19] the form.
    for (std::size_t c4 = 0; c4 < 4; ++c4) SensorFilter(sensor_form_at(th[19]), th[15 + c4], dt_).apply(y[c4]);
  }


 public:
  std::vector<double> effect_term(const std::string& cause, const std::vector<double>& th) const override {
    if (cause != "damper_asymmetry") return {};
    // Extra corner-1 damper force at the measured rate, over the spring rate:
    // a displacement-equivalent [m] so that it shares the residual's axis.
    std::vector<double> out(rate1_.size());
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = th[0] * th[14] * std::tanh(rate1_[i] / kRateBand) * rate1_[i] / th[2];
    return out;
  }

 private:
  static HalfCarParams load_params(const std::string& path) {
    // --config, else the shipped config when run from the source tree, else
    // the built-in defaults (the same nominal pitch-plane set).
    std::string file = path;
    if (file.empty() && std::filesystem::exists("config/half_car.yaml")) file = "config/half_car.yaml";
    if (file.empty()) return HalfCarParams{};
    return load_replay_config(file, RigKind::kHalfCar).half_car;
  }
  // Centrifugal roll moment of the config's curve (roll plane): a known input.
  double roll_moment(double t) const {
    if (m_roll_full_ == 0.0) return 0.0;
    const double since = t - p_.curve_start_time;
    if (since < 0.0) return 0.0;
    if (p_.curve_ramp_time > 0.0 && since < p_.curve_ramp_time) return m_roll_full_ * since / p_.curve_ramp_time;
    return m_roll_full_;
  }

  HalfCarParams p_;
  double m_roll_full_ = 0.0;
  std::vector<double> t_;
  std::array<std::vector<double>, 2> zr_, f_;
  double dt_ = 0.0;
  int decimate_ = 1;
  bool active_ = false;
  double lever_[2] = {0, 0}, static_load_[2] = {0, 0};
  double x0_[4] = {0, 0, 0, 0}, v0_[4] = {0, 0, 0, 0};
  std::vector<double> rate1_, vu1_, df1_, load_;
  std::vector<Output> outputs_;
};

}  // namespace

std::unique_ptr<RigModel> make_half_car_model(const RunFile& run, const RigModelOptions& options) {
  return std::make_unique<HalfCarDiagModel>(run, options);
}

}  // namespace rigctl::diag
