// Diagnosis sub-model of the flexible-bladder rotary pneumatic servo (seed 002,
// docs/rig-models.md section 2): closed-loop replay of the measured
// demand theta_d through the rig's own P + velocity + differential-pressure
// controller (rt/pvp_controller, gains from the config) and a reduced plant:
//
//   valve    x_o = k_sol G(u + u0; delta)    dither-averaged opening (below)
//   chambers d(dp)/dt = n (R T / V) (2 C1 x_o - C2 dp) - 2 n (Pq alpha / V) omega
//   rotor    I domega/dt = alpha dp - b omega - T_step - T_elastic - T_c tanh(omega/eps) + T_stop
//
// Only dp = p_a - p_b is a state: with the Shearer-linearised, antisymmetric
// valve flows the sum p_a + p_b obeys d/dt = -n (R T / V) C2 (p_a + p_b) and
// stays at its initial 0, so it cannot influence anything measured.
//
// Outputs: theta and dp as the transducers report them (delayed by the
// sensor_delay candidate), scored by fit percent.
//
// Dither (50 Hz, 1.5 V in the shipped config) is part of the rig, not a cause,
// and stays in the replay, but averaged instead of integrated: the chambers
// (tau = V / (gamma R T C2) = 0.53 s) and the load (about 1 Hz) are far slower
// than 50 Hz, so over a dither period the flow is the mean of the valve's
// static characteristic over the dither phase, G(w) = mean_phi g(w + A sin phi)
// (a dual-input describing function), and the pressure carries a 50 Hz ripple
// driven by the fundamental of g. Both have closed forms (half_wave()), so the
// replay runs at 4 sub-steps per 2.5 ms period instead of the plant's 10
// with a sine inside, and the averaged characteristic is smooth in every
// parameter even though the valve's dead band is sharp: what the fit needs.
// The ripple term assumes the dither is phase-locked to the run's time base
// (sin(2 pi f t), t from the run file), which the simulator's and a
// DAC-generated dither are; `# dither_phase_rad: ...` in the run file's
// metadata sets another phase.
//
// Candidate effects (docs/diagnosis.md 2.2), each null gives the baseline:
//  * bladder_hysteresis: the seed's trapezoid as a smooth two-part element, a
//    step part h_s tanh(omega/eps) plus a Dahl element T_e z with
//    dz/dtheta = (1 - sign(omega) z) / theta_r: after a reversal the torque
//    jumps by 2 h_s, then follows the travel over a few theta_r and
//    saturates. Rate independent like the bladder; not the plant's linear
//    ramp with a stick/slip state (plant/bladder_hysteresis.*).
//  * coulomb_friction: T_c tanh(omega / eps): a full jump at the reversal,
//    flat in travel (the plant's brake is exact stick/slip).
//  * polytropic_exponent: heat exchange with the chamber walls. n scales the
//    chamber pressure rate; slow motion leaves the gas time to exchange heat
//    (towards isothermal, 1), fast motion does not (adiabatic, 1.4):
//    n(omega) = n + (1.4 - n) x / sqrt(1 + x^2), x = k_h |omega|, the
//    magnitude of a first-order thermal lag's high-pass with the rotor
//    speed standing for the compression's rate (null n = 1.4). k_h = 0 is
//    a constant exponent, a change of n / V, which the calibrated chamber
//    volume V also makes: only V's prior tells the two apart; the speed
//    dependence is a signature V has not.
//  * valve_null_offset: u0 added to the command before the valve.
//  * valve_deadband: overlap delta [V] of a sharp dead zone, seen through the
//    dither average (smooth).
//  * sensor_delay: theta and dp reach the controller and the record tau late
//    (linear interpolation; the simulator's delay line is cubic).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "config/rig_config.hpp"
#include "rt/control/pvp_controller.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/models/controller_from_record.hpp"
#include "tools/diagnosis/rigs.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {

namespace {

constexpr double kPi = std::numbers::pi;
// The baseline's chamber gas: air compressed too fast to exchange heat.
constexpr double kAdiabaticExponent = 1.4;

// Smoothing speed of the sign-like torques [rad/s]. The rig's motions are
// 0.05-1 rad/s; at 2e-3 rad/s a load pushed at 90 % of the friction level
// creeps at 3 mrad/s (eps atanh 0.9), a few 0.5 mrad potentiometer steps over
// a 1.2 s hold: close to the plant's true stick. The steep slope T_c / eps
// this gives is why the rotor's speed is updated semi-implicitly.
constexpr double kEps = 2e-3;
// Without dither the dead zone would be a kink: average it over this small
// amplitude instead [V] (a few 12-bit DAC steps; a softplus-like rounding).
constexpr double kMinSmoothingV = 0.05;
constexpr int kSubsteps = 2;  // 1.25 ms, second-order split below: halving it changes the clean fit by < 0.02 pp

// Mean and 50 Hz fundamental (coefficient of sin phi) of max(w + A sin phi, 0)
// over a uniform phase, for A > 0. With c = clamp(-w/A), a = asin(c):
// mean = (w (pi/2 - a) + A cos a) / pi, fundamental = (2 w cos a + A ((pi - 2a)/2 + sin a cos a)) / pi.
struct HalfWave {
  double mean, fundamental;
};
HalfWave half_wave(double w, double A) {
  const double c = std::clamp(-w / A, -1.0, 1.0);
  const double a = std::asin(c), ca = std::sqrt(std::max(0.0, 1.0 - c * c));
  return {(w * (0.5 * kPi - a) + A * ca) / kPi, (2.0 * w * ca + A * (0.5 * (kPi - 2.0 * a) + c * ca)) / kPi};
}

// Opening in volts of the valve with overlap delta and spool limit Lv, both in
// volts of command: g(v) = dz_delta(clamp(v, -Lv, Lv)) = max(v - delta, 0) -
// max(v - Lv, 0) - max(-v - delta, 0) + max(-v - Lv, 0), averaged over the
// dither phase at command w (each term a half_wave()).
HalfWave dithered_opening(double w, double A, double delta, double Lv) {
  // No overlap and the dithered command inside the spool limit: linear.
  if (delta <= 0.0 && std::abs(w) + A <= Lv) return {w, A};
  const auto p1 = half_wave(w - delta, A), p2 = half_wave(w - Lv, A);
  const auto n1 = half_wave(-w - delta, A), n2 = half_wave(-w - Lv, A);
  return {p1.mean - p2.mean - n1.mean + n2.mean, p1.fundamental - p2.fundamental + n1.fundamental - n2.fundamental};
}

class PneumaticRotaryModel : public RigModel {
 public:
  PneumaticRotaryModel(const RunFile& run, const RigModelOptions& o) : t_(run.t), dt_(run.dt) {
    std::string source = "nominal parameters (built-in defaults = config/pneumatic_rotary.yaml's top level)";
    std::string path = o.config_path;
    if (path.empty() && std::filesystem::exists("config/pneumatic_rotary.yaml")) path = "config/pneumatic_rotary.yaml";
    if (!path.empty()) {
      // The loader gives a pneumatic_rotary config its own controller, pvp (rig_of).
      const auto cfg = load_replay_config(path, RigKind::kPneumaticRotary);
      p_ = cfg.pneumatic_rotary;
      pvp_ = cfg.controller.pvp;
      source = path;
    }
    if (std::abs(run.dt - pvp_.period_s) > 0.01 * pvp_.period_s)
      throw RunFileError("pneumatic_rotary: the closed-loop replay runs the controller at its period " +
                         std::to_string(pvp_.period_s) + " s, but the run file is sampled every " +
                         std::to_string(run.dt) + " s");
    pvp_.angle_input = 0;
    pvp_.pressure_input = 1;
    pvp_.output_index = 0;
    source_ = source + "; " + calibrate_pvp(pvp_, run.col("theta_d"), run.col("theta"), run.col("dp"), run.col("u"));
    theta_d_ = run.col("theta_d");
    outputs_ = {{"theta", run.col("theta")}, {"dp", run.col("dp")}};
    u_meas_ = run.col("u");
    dither_phase_ = run.meta_number("dither_phase_rad").value_or(0.0);
    const double W = 2.0 * kPi * p_.dither_frequency;
    for (double t : t_) {
      sin_.push_back(std::sin(W * t + dither_phase_));
      cos_.push_back(std::cos(W * t + dither_phase_));
    }
    const std::size_t n0 = std::min<std::size_t>(8, t_.size());  // one dither period at 2.5 ms
    for (std::size_t i = 0; i < n0; ++i) {
      theta0_ += outputs_[0].measured[i] / static_cast<double>(n0);
      dp0_ += outputs_[1].measured[i] / static_cast<double>(n0);
    }
    dp0_window_ = n0;
    omega_ = central_diff(outputs_[0].measured, dt_);
    travel_ = travel_since_reversal(outputs_[0].measured);
  }

  RunFileRig rig() const override { return RunFileRig::kPneumaticRotary; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }

  std::vector<ParamSpec> baseline() const override {
    // The payload is the least certain nominal value (the paper runs 1.7 and
    // 0.4 kg m^2); a viscous term lets the baseline take up damping that is
    // not an effect of the library before an effect is credited with it.
    // The rest of the rig's uncertain values with priors of their tolerance
    // (5 %: valve coefficients, volume, quiescent pressure, moment of area,
    // dither amplitude), so a rig a few per cent off nominal is calibrated
    // before any effect is credited with the difference.
    const auto& p = p_;
    // The payload: the least certain value (the paper runs 1.7 and 0.4 kg m^2
    // on one rig), so a wide prior of 30 %: a strong effect must not be able
    // to drag it to its bound before any candidate is tried.
    return {Prior("I", "kg m^2", p.inertia, 0.30, 0.05, 20.0),
            P("b", "N m s/rad", 0.0, 0.0, 100.0, 0.5),
            Prior("C1", "kg/(s m)", p.flow_gain, 0.05),
            Prior("C2", "kg/(s Pa)", p.flow_pressure_coefficient, 0.05),
            Prior("V", "m^3", p.chamber_volume, 0.05),
            Prior("Pq", "Pa", p.quiescent_pressure, 0.05),
            Prior("alpha", "m^3/rad", p.first_moment, 0.05),
            Prior("dither", "V", std::max(p.dither_amplitude, 1e-3), 0.05)};
  }
  std::vector<EffectSpec> effects() const override {
    return {
        {"bladder_hysteresis",
         {P("h_s", "N m", 0.5, 0.0, 30.0, 1.0, 0.0, true), P("T_e", "N m", 0.5, 0.0, 30.0, 1.0, 0.0, true),
          P("theta_r", "rad", 0.015, 0.002, 0.3, 0.02, 0.015, false, {0.005, 0.05})},
         "bladder-distortion hysteresis (seed 002 trapezoid, smooth form): a step h_s tanh(omega/eps) at each "
         "reversal plus a rate-independent Dahl element T_e z, dz/dtheta = (1 - sign(omega) z)/theta_r, that "
         "follows the travel since the reversal over a few theta_r and then saturates; half-width H = h_s + T_e"},
        {"coulomb_friction",
         {P("T_c", "N m", 0.5, 0.0, 30.0, 1.0, 0.0, true)},
         "Coulomb friction T_c tanh(omega/eps) on the rotor: full jump at each reversal, flat in travel"},
        {"polytropic_exponent",
         // k_h: 1 / the rotor speed at which the compression is half-way
         // too fast for heat exchange; 0 (a constant n, the boundary a
         // constant-exponent gas reaches) to 50 s/rad (adiabatic above
         // 0.02 rad/s: at any motion of the rig).
         {P("n", "1", 1.3, 0.8, 1.8, 0.2, 1.4, true, {1.05}),
          P("k_h", "s/rad", 2.0, 0.0, 50.0, 2.0, 2.0, false, {0.0, 10.0})},
         "polytropic exponent of the chamber gas, n at rest rising towards 1.4 (adiabatic) with the rotor's "
         "speed: n(omega) = n + (1.4 - n) x / sqrt(1 + x^2), x = k_h |omega| (pressure rate and pneumatic "
         "stiffness scale with it; 1 isothermal): heat exchange with the walls"},
        {"valve_null_offset",
         {P("u0", "V", 0.05, -2.0, 2.0, 0.1, 0.0, true, {-0.1})},
         "valve null offset u0 added to the command before the spool (drift of the neutral)"},
        {"valve_deadband",
         {P("delta", "V", 0.2, 0.0, 3.0, 0.2, 0.0, true, {0.8})},
         "spool overlap: a dead zone of half-width delta [V of command] about null, seen through the dither"},
        {"sensor_delay",
         {P("tau", "s", 0.002, 0.0, 0.05, 0.005, 0.0, true, {0.007, 0.014})},
         "theta and dp transducers late by tau (inside the loop and in the record)"},
    };
  }
  std::string replay() const override {
    return "closed-loop replay: theta_d through the rig's P+V+dP controller (rt/pvp_controller; " + source_ +
           ") and the reduced pneumatic plant (valve, differential chamber pressure, rotor), controller at the run's "
           "period with the command held, " + std::to_string(kSubsteps) +
           " semi-implicit sub-steps per period; the valve dither is kept, averaged over its phase (mean flow and "
           "50 Hz pressure ripple in closed form)";
  }

  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    run(th, y, nullptr);
  }

  // Where an effect can enter (docs/diagnosis.md 3); the order is run()'s
  // `place`. Steps of the linearisation: a few per mille of the signals.
  std::vector<Place> places() const override {
    return {{"a torque on the rotor", "N m", 0.01, -1, false, {"bladder_hysteresis", "coulomb_friction"}},
            {"a flow into the chambers (a rate of dp)", "Pa/s", 100.0, -1, false,
             {"polytropic_exponent", "valve_deadband", "valve_null_offset"}},  // the valve's flow enters here
            {"an offset of the valve command", "V", 1e-3, -1, false, {"valve_null_offset", "valve_deadband"}},
            {"an error on the theta sensor (the feedback)", "rad", 1e-4, 0, true, {"sensor_delay"}},
            {"an error on the dp sensor (fed back)", "Pa", 10.0, 1, true, {"sensor_delay"}}};
  }
  std::vector<Feature> features() const override {
    // Outputs: theta 0, dp 1 (Feature::from).
    return {{"omega", FeatureKind::kVelocity, omega_, {0}},
            {"u", FeatureKind::kCommand, u_meas_, {0, 1}},  // the controller's law of theta and dp
            {"dp", FeatureKind::kValue, outputs_[1].measured, {1}},
            {"d(dp)/dt", FeatureKind::kValue, central_diff(moving_mean(outputs_[1].measured, 8), dt_), {1}},
            {"theta", FeatureKind::kPosition, outputs_[0].measured, {0}}};
  }
  void simulate_with_input(const std::vector<double>& th, std::size_t place, const std::vector<double>& d,
                           std::vector<std::vector<double>>& y) const override {
    run(th, y, nullptr, 0, place, &d);
  }

  Indicator indicator(const std::string& cause) const override {
    if (cause == "bladder_hysteresis" || cause == "coulomb_friction")
      return {"travel since the last reversal, signed by the direction [rad]", travel_};
    if (cause == "valve_deadband" || cause == "valve_null_offset") return {"controller output u [V]", u_meas_};
    if (cause == "polytropic_exponent") {
      return {"d(dp)/dt [Pa/s] (measured, 50 Hz ripple averaged)", central_diff(moving_mean(outputs_[1].measured, 8), dt_)};
    }
    return {"d(theta)/dt [rad/s] (measured)", omega_};
  }

  // The torque the effect adds, along the fitted replay, as the equivalent
  // differential pressure T / alpha [Pa]: comparable with a dp residual.
  std::vector<double> effect_term(const std::string& cause, const std::vector<double>& th) const override {
    if (cause != "bladder_hysteresis" && cause != "coulomb_friction") return {};
    std::vector<std::vector<double>> y;
    std::vector<double> torque;
    run(th, y, &torque, cause == "coulomb_friction" ? 2 : 1);
    for (auto& v : torque) v /= th[6];
    return torque;
  }

 private:
  // which: 1 hysteresis torque, 2 Coulomb torque, into *torque per sample.
  // d: the where's signal at places()[place], per sample (null: none).
  void run(const std::vector<double>& th, std::vector<std::vector<double>>& y, std::vector<double>* torque,
           int which = 0, std::size_t place = 0, const std::vector<double>* d = nullptr) const {
    auto added = [&](std::size_t p, std::size_t k) { return d && place == p ? (*d)[k] : 0.0; };
    const double I = th[0], b = th[1], C1 = th[2], C2 = th[3], V = th[4], Pq = th[5], alpha = th[6], dither = th[7];
    const double hs = th[8], te = th[9], thr = std::max(th[10], 1e-4), tc = th[11], n_rest = th[12],
                 k_h = th[13], u0 = th[14], delta = th[15], tau = th[16];
    const std::size_t N = t_.size();
    y.assign(2, std::vector<double>(N, 0.0));
    if (torque) torque->assign(N, 0.0);
    const auto& p = p_;
    const double gas0 = p.gas_constant * p.supply_temperature / V;  // R T / V; times n
    const double mot0 = Pq * alpha / V;                             // Pq alpha / V; times n
    const bool speed_dependent_n = n_rest != kAdiabaticExponent;
    auto exponent = [&](double omega) {
      if (!speed_dependent_n) return kAdiabaticExponent;
      const double x = k_h * omega;
      return n_rest + (kAdiabaticExponent - n_rest) * std::abs(x) / std::sqrt(1.0 + x * x);
    };
    const double Lv = p.spool_limit / p.solenoid_gain;
    const double A = p.dither ? dither : 0.0;
    const double A_avg = std::max(A, kMinSmoothingV);
    const double W = 2.0 * kPi * p.dither_frequency;
    // dp ripple of a fundamental F [V] of the opening: 2 n R T/V C1 k F (a sin - W cos) / (W^2 + a^2),
    // a = n R T / V C2 (1 / tau_chamber), with n at the rotor's speed.
    // At t_k - tau: the dither phase of t_k turned back by W tau.
    const double cd = std::cos(W * tau), sd = std::sin(W * tau);
    auto ripple = [&](std::size_t k, double fundamental, double n) {
      if (!(A > 0.0)) return 0.0;
      const double gas = n * gas0, leak = gas * C2;
      const double sn = sin_[k] * cd - cos_[k] * sd, cs = cos_[k] * cd + sin_[k] * sd;
      return 2.0 * gas * C1 * p.solenoid_gain / (W * W + leak * leak) * fundamental * (leak * sn - W * cs);
    };
    auto opening = [&](double u) { return dithered_opening(u + u0, A_avg, std::min(delta, 0.99 * Lv), Lv); };

    PvpController ctrl(pvp_);
    ctrl.reset();
    Sample sample{};
    Command cmd{};
    ControllerTerms terms{};

    std::vector<double> h_theta(N), h_dp(N), h_fund(N);
    double fund_prev = opening(0.0).fundamental;
    // Slow part of dp at the start: the measured mean over one dither period
    // less the modelled ripple's mean there.
    double rip0 = 0.0;
    for (std::size_t i = 0; i < dp0_window_; ++i) rip0 += ripple(i, fund_prev, n_rest) / static_cast<double>(dp0_window_);
    double theta = theta0_, omega = 0.0, dp = dp0_ - rip0, z = 0.0;
    const double h = dt_ / kSubsteps;
    const double S = hs + tc;  // level of the sign-like torques
    const double shift = tau / dt_;
    const bool sign_like = S > 0.0, dahl = te > 0.0;
    for (std::size_t k = 0; k < N; ++k) {
      h_theta[k] = theta;
      h_dp[k] = dp;
      h_fund[k] = fund_prev;  // the ripple at t_k comes from the opening over the period before it
      const double s = std::min(static_cast<double>(k), static_cast<double>(k) - shift);
      const double theta_m = at(h_theta, s) + added(3, k);
      const double dp_m = at(h_dp, s) + ripple(k, at(h_fund, s), exponent(omega)) + added(4, k);
      y[0][k] = theta_m;
      y[1][k] = dp_m;
      sample.value[0] = theta_m;
      sample.value[1] = dp_m;
      ctrl.update(theta_d_[k], sample, cmd, terms);
      const auto op = opening(cmd.value[0] + added(2, k));
      const double torque_in = added(0, k), rate_in = added(1, k);
      fund_prev = A > 0.0 ? op.fundamental : 0.0;
      const double flow = 2.0 * C1 * p.solenoid_gain * op.mean;  // 2 C1 x_o [kg/s]
      // Each sub-step is split symmetrically (Strang): half a step of the
      // chambers, the rotor over the whole step, the other half of the
      // chambers with the new speed; the angle and the Dahl travel use the
      // mean speed. Second order, so the sub-step leaves no O(h) time shift
      // between angle and pressure that would pass for a sensor delay.
      for (int j = 0; j < kSubsteps; ++j) {
        const double n = exponent(omega);  // over the sub-step, at its start's speed
        dp += 0.5 * h * (n * (gas0 * flow - gas0 * C2 * dp - 2.0 * mot0 * omega) + rate_in);
        const double th_ = sign_like ? std::tanh(omega / kEps) : 0.0;
        const double T = alpha * dp - te * z + stop_torque(theta + 0.5 * h * omega, omega) + torque_in;
        // Semi-implicit in omega for the stiff tanh and the viscous term.
        const double slope = S / kEps * (1.0 - th_ * th_) + b;
        const double wn = omega + h * (T - S * th_ - b * omega) / (I + h * slope);
        const double wm = 0.5 * (omega + wn);
        theta += h * wm;
        if (dahl) {  // exact for the mean speed over the sub-step
          const double a = wm * std::tanh(wm / kEps) / thr * h;  // >= 0
          const double e = std::exp(-a);
          z = z * e + (wm * h / thr) * (a > 1e-12 ? (1.0 - e) / a : 1.0 - 0.5 * a);
        }
        dp += 0.5 * h * (n * (gas0 * flow - gas0 * C2 * dp - 2.0 * mot0 * wn) + rate_in);
        omega = wn;
      }
      if (torque) {
        const double sg = std::tanh(omega / kEps);
        (*torque)[k] = which == 2 ? tc * sg : hs * sg + te * z;
      }
      if (!std::isfinite(theta) || !std::isfinite(dp)) {
        for (std::size_t j = k; j < N; ++j) y[0][j] = 1e3, y[1][j] = 1e9;
        return;
      }
    }
  }

  double stop_torque(double theta, double omega) const {
    // As the plant's end stops (they only push).
    const auto& p = p_;
    if (theta > p.angle_limit)
      return std::min(0.0, -p.end_stop_stiffness * (theta - p.angle_limit) - p.end_stop_damping * omega);
    if (theta < -p.angle_limit)
      return std::max(0.0, -p.end_stop_stiffness * (theta + p.angle_limit) - p.end_stop_damping * omega);
    return 0.0;
  }

  static std::vector<double> moving_mean(const std::vector<double>& x, std::size_t w) {
    std::vector<double> m(x.size(), 0.0);
    double s = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      s += x[i];
      if (i >= w) s -= x[i - w];
      m[i] = s / static_cast<double>(std::min(i + 1, w));
    }
    return m;
  }

  // Signed travel since the last reversal of the measured angle. A reversal
  // counts once the angle has come back 2 mrad from its extreme (about four
  // LSB of the 12-bit potentiometer, seven noise sigmas), so noise at rest
  // does not restart the count.
  static std::vector<double> travel_since_reversal(const std::vector<double>& th) {
    constexpr double kBand = 2e-3;
    std::vector<double> out(th.size(), 0.0);
    if (th.empty()) return out;
    int dir = 0;
    double anchor = th[0], extreme = th[0], hi = th[0], lo = th[0];
    for (std::size_t i = 0; i < th.size(); ++i) {
      const double x = th[i];
      if (dir == 0) {  // first motion: from the start, once it leaves the band
        hi = std::max(hi, x), lo = std::min(lo, x);
        if (hi - lo > kBand) dir = x >= hi ? 1 : -1, anchor = dir > 0 ? lo : hi, extreme = x;
      } else if (dir > 0) {
        if (x > extreme) extreme = x;
        else if (x < extreme - kBand) dir = -1, anchor = extreme, extreme = x;
      } else {
        if (x < extreme) extreme = x;
        else if (x > extreme + kBand) dir = 1, anchor = extreme, extreme = x;
      }
      out[i] = dir * std::abs(x - anchor);
    }
    return out;
  }

  std::vector<double> t_, theta_d_, u_meas_, omega_, travel_;
  std::vector<double> sin_, cos_;  // dither phase at each sample
  double dt_;
  PneumaticRotaryParams p_;
  PvpConfig pvp_;
  std::string source_;
  double dither_phase_ = 0.0, theta0_ = 0.0, dp0_ = 0.0;
  std::size_t dp0_window_ = 1;
  std::vector<Output> outputs_;
};

}  // namespace

std::unique_ptr<RigModel> make_pneumatic_rotary_model(const RunFile& run, const RigModelOptions& options) {
  return std::make_unique<PneumaticRotaryModel>(run, options);
}

}  // namespace rigctl::diag
