// Sub-models of the diagnosis, one per rig kind, with a candidate effect for
// every cause id of docs/run-files.md 2.5 (stubs are marked).
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/rigs.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {

namespace {

// ------------------------------------------------------------------ linear_axis

// Rigid body M x'' = F - Fv x' - Fc sign(x') - offset under the axis's known
// closed loop (EMPS): v = kp kv (x_ref - x) - kv xdot_f, xdot_f the backward
// difference of x_f(k) = (x(k) + x(k-1)) / 2, saturated at +-sat, F = g v.
// x_ref is replayed; x and F are the simulated outputs (closed-loop replay as
// the EMPS package's Simulation_EMPS).
class LinearAxisModel : public RigModel {
 public:
  LinearAxisModel(const RunFile& run, const RigModelOptions& o) : t_(run.t), dt_(run.dt) {
    if (!run.has("x_ref"))
      throw RunFileError("linear_axis: the closed-loop replay needs the reference column 'x_ref'");
    xref_ = run.col("x_ref");
    f_ext_ = run.has("f_ext") ? run.col("f_ext") : std::vector<double>(t_.size(), 0.0);
    auto get = [&](const std::string& key) -> double {
      if (!o.config_path.empty()) {
        YAML::Node n = YAML::LoadFile(o.config_path);
        if (n[key]) return n[key].as<double>();
      }
      const auto v = run.meta_number(key);
      if (!v)
        throw RunFileError("linear_axis: loop parameter '" + key +
                           "' missing (give it as a metadata line '# " + key + ": ...' or in --config)");
      return *v;
    };
    kp_ = get("kp");
    kv_ = get("kv");
    gain_ = get("drive_gain_n_per_v");
    sat_ = get("saturation_v");
    outputs_ = {{"u", run.col("u")}, {"x", run.col("x")}};
    vel_ = central_diff(run.col("x"), dt_);
  }
  RunFileRig rig() const override { return RunFileRig::kLinearAxis; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }
  std::vector<ParamSpec> baseline() const override {
    return {P("M", "kg", 100.0, 1.0, 1e4, 100.0), P("Fv", "N s/m", 200.0, 0.0, 1e5, 100.0)};
  }
  std::vector<EffectSpec> effects() const override {
    return {
        {"coulomb_friction", {P("Fc", "N", 5.0, 0.0, 1e4, 10.0, 0.0, true)}, "Coulomb friction Fc sign(v) on the axis"},
        {"asymmetric_friction",
         {P("dFc", "N", 0.0, -1e4, 1e4, 5.0, 0.0, true), P("dFv", "N s/m", 0.0, -1e4, 1e4, 50.0, 0.0, true)},
         "friction differs with the direction of motion: Fc+- = Fc +- dFc, Fv+- = Fv +- dFv"},
        {"stribeck_friction",
         {P("Fs", "N", 5.0, 0.0, 1e4, 10.0, 0.0, true), P("vs", "m/s", 0.005, 1e-4, 0.03, 0.01, 0.0, false, {0.02})},
         "Stribeck excess Fs exp(-(v/vs)^2) over the Coulomb level at low speed"},
        {"force_offset", {P("offset", "N", 0.0, -1e4, 1e4, 5.0, 0.0, true)}, "constant force offset on the axis"},
        {"compliance",
         {P("compliance", "um/N", 0.5, 0.0, 1e3, 1.0, 0.0, true, {0.05, 5.0})},
         "an unmodelled flexible mode: the load (half the mass) on a spring of 1/compliance behind the measured drive "
         "side"},
        {"sensor_delay", {P("tau", "s", 0.0005, 0.0, 0.05, 0.001, 0.0, true, {0.002})}, "position measured late by tau"},
    };
  }
  std::string replay() const override {
    return "closed-loop replay: x_ref through the axis's known P position / P velocity loop (kp, kv, drive gain, "
           "saturation from the run's metadata) and the rigid-body model, force held over each period, 4 sub-steps "
           "with an implicit (stick-capable) friction update";
  }
  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    run(th, y, 0, nullptr);
  }
  // Where an effect can enter (docs/diagnosis.md 3): run()'s `place`.
  std::vector<Place> places() const override {
    return {{"a force on the axis", "N", 0.1, -1, false,
             {"coulomb_friction", "asymmetric_friction", "stribeck_friction", "force_offset", "compliance"}},
            {"an error on the x sensor (the feedback)", "m", 1e-6, 1, true, {"sensor_delay"}}};
  }
  std::vector<Feature> features() const override {
    return {{"v", FeatureKind::kVelocity, vel_, {1}},
            {"acceleration", FeatureKind::kValue, central_diff(vel_, dt_), {1}},
            {"x", FeatureKind::kPosition, outputs_[1].measured, {1}}};
  }
  void simulate_with_input(const std::vector<double>& th, std::size_t place, const std::vector<double>& d,
                           std::vector<std::vector<double>>& y) const override {
    run(th, y, place, &d);
  }
  Indicator indicator(const std::string& cause) const override {
    if (cause == "compliance") return {"acceleration [m/s^2]", central_diff(vel_, dt_)};
    return {"velocity [m/s] (from measured x)", vel_};
  }

 private:
  // added: the where's signal at places()[place] per sample (null: none).
  void run(const std::vector<double>& th, std::vector<std::vector<double>>& y, std::size_t place,
           const std::vector<double>* added) const {
    auto extra = [&](std::size_t p, std::size_t i) { return added && place == p ? (*added)[i] : 0.0; };
    const double M = th[0], Fv = th[1], Fc = th[2], dFc = th[3], dFv = th[4], Fs = th[5], vs = th[6], off = th[7],
                 comp = th[8] * 1e-6, tau = th[9];
    const std::size_t n = t_.size();
    y.assign(2, std::vector<double>(n, 0.0));
    const int sub = 4;
    const double h = dt_ / sub;
    const auto& xm = outputs_[1].measured;
    double x = xm[0], v = 0.0;   // drive side
    double x2 = x, v2 = 0.0;     // load side (compliance)
    const bool flex = comp > 1e-12;
    const double m1 = flex ? 0.5 * M : M, m2 = 0.5 * M;
    const double k = flex ? 1.0 / comp : 0.0, c = flex ? 2.0 * 0.05 * std::sqrt(k * m2) : 0.0;
    const double cp = std::max(0.0, Fc + dFc), cn = std::max(0.0, Fc - dFc);
    const double dp = std::max(0.0, Fv + dFv), dn = std::max(0.0, Fv - dFv);
    std::vector<double> hist(n, x);  // true drive-side position at each sample
    double xm_prev = x, xf_prev = x;
    for (std::size_t i = 0; i < n; ++i) {
      hist[i] = x;
      const double xs = (tau > 0.0 ? at(hist, std::min(static_cast<double>(i), static_cast<double>(i) - tau / dt_)) : x) +
                        extra(1, i);
      const double xf = 0.5 * (xs + xm_prev);
      const double xd = i == 0 ? 0.0 : (xf - xf_prev) / dt_;
      xm_prev = xs;
      xf_prev = xf;
      const double volt = std::clamp(kp_ * kv_ * (xref_[i] - xs) - kv_ * xd, -sat_, sat_);
      const double F = gain_ * volt;
      y[0][i] = F;
      y[1][i] = xs;
      for (int s = 0; s < sub; ++s) {
        double f = F + f_ext_[i] - off + extra(0, i);
        if (flex) f -= k * (x - x2) + c * (v - v2);
        const double g = Fs > 0.0 ? Fs * std::exp(-(v / vs) * (v / vs)) : 0.0;
        v = implicit_velocity(m1, v, f, h, cp + g, cn + g, dp, dn);
        x += h * v;
        if (flex) {
          v2 += h * (k * (x - x2) + c * (v - v2)) / m2;
          x2 += h * v2;
        }
      }
      if (!std::isfinite(x)) {
        for (std::size_t j = i; j < n; ++j) y[0][j] = y[1][j] = 1e6;
        return;
      }
    }
  }

 public:
  std::vector<double> effect_term(const std::string&, const std::vector<double>& th) const override {
    // The fitted friction force at the measured velocity (what the residual of u should follow).
    std::vector<double> f(vel_.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double v = vel_[i];
      const double sgn = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
      const double g = th[5] > 0 ? th[5] * std::exp(-(v / th[6]) * (v / th[6])) : 0.0;
      f[i] = (v >= 0 ? th[1] + th[4] : th[1] - th[4]) * v + sgn * ((v >= 0 ? th[2] + th[3] : th[2] - th[3]) + g) +
             th[7];
    }
    return f;
  }

 private:
  std::vector<double> t_, xref_, f_ext_, vel_;
  double dt_, kp_ = 0, kv_ = 0, gain_ = 0, sat_ = 0;
  std::vector<Output> outputs_;
};

// ------------------------------------------------------------------ damper

// Imposed displacement, measured force. Baseline: memoryless viscous with a
// voltage-dependent coefficient and a force offset, f = (c0 + c1 u) v + f0.
class DamperModel : public RigModel {
 public:
  DamperModel(const RunFile& run, const RigModelOptions& o) {
    const int dec = o.decimate > 0 ? o.decimate : std::max(1, static_cast<int>(std::lround(0.001 / run.dt)));
    const auto& x = run.col("x");
    const auto& f = run.col("f");
    const auto v = run.has("v") ? run.col("v") : central_diff(x, run.dt);
    const auto u = run.has("u") ? run.col("u") : std::vector<double>(x.size(), 0.0);
    has_u_ = run.has("u");
    for (std::size_t i = 0; i < x.size(); i += static_cast<std::size_t>(dec)) {
      t_.push_back(run.t[i]);
      x_.push_back(x[i]);
      v_.push_back(v[i]);
      u_.push_back(u[i]);
      fm_.push_back(f[i]);
    }
    dt_ = run.dt * dec;
    decimate_ = dec;
    outputs_ = {{"f", fm_}};
    // Least-squares start of the baseline.
    double A[3][3] = {}, b[3] = {};
    for (std::size_t i = 0; i < t_.size(); ++i) {
      const double r[3] = {v_[i], u_[i] * v_[i], 1.0};
      for (int p = 0; p < 3; ++p) {
        b[p] += r[p] * fm_[i];
        for (int q = 0; q < 3; ++q) A[p][q] += r[p] * r[q];
      }
    }
    if (!has_u_) A[1][1] += 1.0;
    for (int c = 0; c < 3; ++c)  // Gauss-Jordan, 3x3 SPD
      for (int r = 0; r < 3; ++r)
        if (r != c) {
          const double m = A[r][c] / A[c][c];
          for (int q = 0; q < 3; ++q) A[r][q] -= m * A[c][q];
          b[r] -= m * b[c];
        }
    for (int p = 0; p < 3; ++p) ls_[p] = b[p] / A[p][p];
  }
  RunFileRig rig() const override { return RunFileRig::kDamper; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }
  std::vector<ParamSpec> baseline() const override {
    return {P("c0", "N s/m", ls_[0], -1e7, 1e7, std::max(100.0, std::abs(ls_[0]))),
            P("c1", "N s/m/V", ls_[1], -1e7, 1e7, std::max(100.0, std::abs(ls_[1]))),
            P("f0", "N", ls_[2], -1e6, 1e6, 10.0)};
  }
  std::vector<EffectSpec> effects() const override {
    return {
        {"hysteresis",
         {P("a0", "N", 100.0, -1e6, 1e6, 100.0, 0.0, true), P("a1", "N/V", 100.0, -1e6, 1e6, 100.0, 0.0, true),
          P("rho", "1/m", 500.0, 1.0, 1e5, 500.0, 0.0, false, {100.0, 3000.0})},
         "Dahl internal state z' = rho (v - |v| z), force (a0 + a1 u) z: the force depends on the path"},
        {"command_lag",
         {P("tau_u", "s", 0.01, 0.0, 1.0, 0.01, 0.0, true, {0.003, 0.05})},
         "the voltage acts through a first-order lag tau_u (current driver, field build-up)"},
        {"coulomb_friction",
         {P("fc0", "N", 50.0, -1e6, 1e6, 100.0, 0.0, true), P("fc1", "N/V", 50.0, -1e6, 1e6, 100.0, 0.0, true)},
         "Coulomb (Bingham) force (fc0 + fc1 u) tanh(v / 0.01 m/s)"},
        {"damper_asymmetry", {P("dc", "N s/m", 0.0, -1e7, 1e7, 100.0, 0.0, true)},
         "rebound and compression damping differ: extra dc v tanh(v / 0.01 m/s)"},
        {"stiffness", {P("k", "N/m", 0.0, -1e9, 1e9, 1e4, 0.0, true)}, "a spring force k x in parallel"},
        {"sensor_delay", {P("tau_f", "s", 0.001, 0.0, 0.05, 0.001, 0.0, true, {0.005})}, "force measured late by tau_f"},
    };
  }
  std::string replay() const override {
    return "open-loop replay: measured x, v and u drive the damper model, the force is the output (decimated by " +
           std::to_string(decimate_) + " to " + std::to_string(static_cast<int>(std::lround(1.0 / dt_))) + " Hz)";
  }
  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    const double c0 = th[0], c1 = th[1], f0 = th[2], a0 = th[3], a1 = th[4], rho = th[5], tau_u = th[6], fc0 = th[7],
                 fc1 = th[8], dc = th[9], k = th[10], tau_f = th[11];
    const std::size_t n = t_.size();
    y.assign(1, std::vector<double>(n));
    const double lag = tau_u > 1e-6 ? std::exp(-dt_ / tau_u) : 0.0;
    double ue = u_[0], z = 0.0;
    const bool hyst = a0 != 0.0 || a1 != 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = v_[i];
      const double f = (c0 + c1 * ue) * v + f0 + (a0 + a1 * ue) * z + (fc0 + fc1 * ue) * std::tanh(v / 0.01) +
                       dc * v * std::tanh(v / 0.01) + k * x_[i];
      y[0][i] = f;
      if (hyst) {  // exact for v constant over the step
        const double s = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
        z = s + (z - s) * std::exp(-rho * std::abs(v) * dt_);
      }
      const double un = i + 1 < n ? u_[i + 1] : u_[i];
      ue = lag > 0.0 ? un + (ue - un) * lag : un;
    }
    delay(y[0], tau_f, dt_);
  }
  // The force is the only output and the model is memoryless but for its
  // effects: every cause enters as a missing force (docs/diagnosis.md 3),
  // and the regressors say which.
  std::vector<Place> places() const override {
    return {{"a force of the damper (on f)", "N", 1.0, -1, false,
             {"hysteresis", "command_lag", "coulomb_friction", "damper_asymmetry", "stiffness", "sensor_delay"}}};
  }
  // Not a sensor's error (whose library is its own channel's): the damper's
  // force, free to follow the motion and the command.
  void simulate_with_input(const std::vector<double>& th, std::size_t, const std::vector<double>& d,
                           std::vector<std::vector<double>>& y) const override {
    simulate(th, y);
    for (std::size_t i = 0; i < y[0].size(); ++i) y[0][i] += d[i];
  }
  std::vector<Feature> features() const override {
    std::vector<double> uv(v_.size());
    for (std::size_t i = 0; i < uv.size(); ++i) uv[i] = u_[i] * v_[i];
    return {{"v", FeatureKind::kVelocity, v_, {}},
            {"u", FeatureKind::kValue, u_, {}},
            {"u v", FeatureKind::kValue, uv, {}},
            {"x", FeatureKind::kPosition, x_, {}},
            {"du/dt", FeatureKind::kValue, central_diff(u_, dt_), {}}};
  }
  Indicator indicator(const std::string& cause) const override {
    if (cause == "command_lag") return {"du/dt [V/s]", central_diff(u_, dt_)};
    if (cause == "stiffness") return {"x [m]", x_};
    if (cause == "sensor_delay") return {"df/dt [N/s]", central_diff(fm_, dt_)};
    return {"v [m/s]", v_};
  }
  std::vector<double> effect_term(const std::string& cause, const std::vector<double>& th) const override {
    if (cause != "hysteresis") return {};
    std::vector<double> out(t_.size());
    double z = 0.0;
    for (std::size_t i = 0; i < t_.size(); ++i) {
      out[i] = (th[3] + th[4] * u_[i]) * z;
      const double s = v_[i] > 0 ? 1.0 : (v_[i] < 0 ? -1.0 : 0.0);
      z = s + (z - s) * std::exp(-th[5] * std::abs(v_[i]) * dt_);
    }
    return out;
  }

 private:
  std::vector<double> t_, x_, v_, u_, fm_;
  double dt_ = 0.0, ls_[3] = {0, 0, 0};
  int decimate_ = 1;
  bool has_u_ = false;
  std::vector<Output> outputs_;
};

}  // namespace

RigConfig load_replay_config(const std::string& path, RigKind rig) {
  RigConfig config = load_rig_config(path);
  if (config.rig != rig) {
    throw RunFileError("--config is a '" + std::string(to_string(config.rig)) + "' config, not " +
                       std::string(to_string(rig)));
  }
  return config;
}

std::unique_ptr<RigModel> make_rig_model(RunFileRig rig, const RunFile& run, const RigModelOptions& o) {
  switch (rig) {
    case RunFileRig::kLinearAxis: return std::make_unique<LinearAxisModel>(run, o);
    case RunFileRig::kDamper: return std::make_unique<DamperModel>(run, o);
    case RunFileRig::kQuarterCar: return make_quarter_car_model(run, o);
    case RunFileRig::kPneumaticRotary: return make_pneumatic_rotary_model(run, o);
    case RunFileRig::kHalfCar: return make_half_car_model(run, o);
  }
  throw std::logic_error("make_rig_model: rig kind out of range");
}

}  // namespace rigctl::diag
