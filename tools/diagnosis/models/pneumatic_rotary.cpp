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
// (sin(2 pi f t + phase), t from the run file), which the simulator's and a
// DAC-generated dither are. The phase is the rig's timing: `# dither_phase_rad:
// ...` in the run file's metadata states it, else it is read off the
// record's own 50 Hz dp ripple (a rig whose dither starts at another phase,
// or is generated at the loop's rate and held, has its ripple elsewhere: a
// ripple modelled 110 degrees off cost a clean run 15 pp of dp's fit, which a
// filter on dp then "explained" as a sensor delay).
//
// Candidate effects (docs/diagnosis.md 2.2), each null gives the baseline:
//  * bladder_hysteresis: the seed's trapezoid as a smooth two-part element, a
//    step part h_s tanh(omega/eps) plus a Dahl element T_e z with
//    dz/dtheta = (1 - sign(omega) z) / theta_r: after a reversal the torque
//    jumps by 2 h_s, then follows the travel over a few theta_r and
//    saturates. Rate independent like the bladder; not the plant's linear
//    ramp with a stick/slip state (plant/bladder_hysteresis.*).
//  * coulomb_friction: (T_c + dT_s exp(-(omega / 0.01 rad/s)^2)) tanh(omega /
//    eps): a full jump at the reversal, flat in travel, with a stiction
//    excess to break away from rest (the plant's brake is exact stick/slip).
//  * polytropic_exponent, in two forms: the chamber gas exchanging heat with
//    the walls through hA (Newton's law, null 0; the gas's exponent n stays
//    1.4), a temperature state per chamber (their difference; the sum stays
//    at rest as the pressure sum does), or compressed with a constant
//    exponent n (null 1.4, no thermal state). With the net mass flow dm
//    into chamber a and out of b and the volume rate 2 alpha omega:
//      d(dp)/dt = n (R T / V dm - 2 Pq alpha / V omega) - (1.4 - 1) hA vth / V
//      d(vth)/dt = T (d(dp)/dt / Pq + 2 alpha omega / V - R T dm / (Pq V))
//    so slow motion leaves the gas time to reach the walls' temperature
//    (isothermal), fast motion does not (adiabatic). A constant n below 1.4
//    is a change of n / V, which the calibrated chamber volume also makes:
//    only V's prior tells the two apart; hA's dependence on the motion's
//    rate is a signature V has not.
//  * valve_null_offset: u0 added to the command before the valve.
//  * valve_deadband: overlap delta [V] of a sharp dead zone, seen through the
//    dither average (smooth).
//  * sensor_delay: theta and dp each through a sensor of its own group delay
//    (tau_theta, tau_dp), inside the loop and in the record, in the form that
//    fits best (sensor_filter.hpp: pure delay, first-order lag, Bessel or
//    Butterworth of order 2-4).
//
// The loop's I/O timing is calibration, not a cause (docs/diagnosis.md 4):
// t_command (the command takes effect that long after its sample: a
// computation delay, up to a period, beside the hold) and t_sample (the
// sensors are sampled that long before the tick, up to half a period) are
// baseline parameters fitted within their bounds; only a sensor's delay
// beyond what they explain is a sensor_delay.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "config/rig_config.hpp"
#include "rt/control/pvp_controller.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/models/controller_from_record.hpp"
#include "tools/diagnosis/rigs.hpp"
#include "tools/diagnosis/sensor_filter.hpp"
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
// Breakaway of the Coulomb friction's stiction excess: it is felt only while
// the rotor is nearly stuck (a brake's stiction), well below the rig's
// 0.05-1 rad/s motions and above kEps, so the semi-implicit update can hold it.
constexpr double kStribeckSpeed = 0.01;  // [rad/s]

// Parameter indices (baseline, then effects in effects() order).
enum : std::size_t {
  kI, kB, kC1, kC2, kV, kPq, kAlpha, kDither,  // baseline: the rig's uncertain values
  kTCmd, kTSample,                             // baseline: the loop's I/O timing
  kHs, kTe, kThetaR,                           // bladder_hysteresis
  kTc, kDTs,                                   // coulomb_friction
  kN, kHA, kGasForm,                           // polytropic_exponent
  kU0,                                         // valve_null_offset
  kDelta,                                      // valve_deadband
  kTauTheta, kTauDp, kSensorFormIndex,         // sensor_delay
  kParamCount
};

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
    const double W = 2.0 * kPi * p_.dither_frequency;
    // The dither's phase against the run's time base is the rig's timing,
    // not a cause: from the metadata where the run states it, else read off
    // the record's own dp ripple (dither_phase_from_ripple).
    const auto stated = run.meta_number("dither_phase_rad");
    dither_phase_ = stated ? *stated : dither_phase_from_ripple(W);
    dither_phase_read_ = !stated;
    dither_phase_source_ = stated ? "stated in the run file" : "read off the record's dp ripple";
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
            Prior("dither", "V", std::max(p.dither_amplitude, 1e-3), 0.05),
            // The loop's I/O timing (docs/diagnosis.md 4): when the command
            // takes effect after its sample (a computation delay, up to a
            // period), and how long before the tick the sensors are sampled
            // (up to half a period). With the output's hold (half a period
            // on average, in the replay) the loop's delay can grow by up to
            // two periods. A rig's own, not a cause: calibrated within these
            // bounds from rigctl's own convention (sampled at the tick,
            // applied at once). Wider (two periods and one) they took 7.5 ms
            // of a 10 ms sensor delay, leaving it 0.5 pp.
            Timing("t_command", 0.0, dt_, 0.5 * dt_),
            Timing("t_sample", 0.0, 0.5 * dt_, 0.5 * dt_)};
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
         {P("T_c", "N m", 0.5, 0.0, 30.0, 1.0, 0.0, true), P("dT_s", "N m", 0.0, 0.0, 30.0, 1.0, 0.0, true)},
         "Coulomb friction on the rotor, (T_c + dT_s exp(-(omega/0.01 rad/s)^2)) tanh(omega/eps): a full jump at "
         "each reversal, flat in travel, with a stiction excess dT_s to break away from rest"},
        {"polytropic_exponent",
         // hA: the heat-transfer coefficient of the chamber walls. The gas
         // of a chamber (m c_v = Pq V / ((1.4 - 1) T), about 1 J/K) follows
         // its walls in m c_v / hA: 10 ms at 100 W/K (near isothermal at
         // any motion of the rig), 1 s at 1 W/K.
         // Two forms that do not nest: with heat exchange the gas's own
         // exponent stays 1.4 and hA sets how far from adiabatic it gets (a
         // large hA is isothermal whatever n, so n and hA free together
         // traded against each other: n 1.11 for a world of constant 1.0);
         // a constant exponent n has no thermal state. Each form's other
         // parameter is unused (undetermined). Both forms are screened: an
         // isothermal gas of constant exponent was not among the best three
         // when screened as heat exchange alone.
         {P("n", "1", 1.3, 0.8, 1.8, 0.2, 1.4, true, {1.05}),
          P("hA", "W/K", 2.0, 0.0, 100.0, 5.0, 0.0, true, {20.0}), FormIndex({1.0})},
         "the chamber gas: exchanging heat with the walls through hA (Newton's law; a temperature state per "
         "chamber), so the pressure rate and the pneumatic stiffness fall from adiabatic toward isothermal as the "
         "motion slows; or compressed with a constant exponent n (1.4 adiabatic, 1 isothermal)",
         {"heat_exchange", "constant_exponent"}},
        {"valve_null_offset",
         {P("u0", "V", 0.05, -2.0, 2.0, 0.1, 0.0, true, {-0.1})},
         "valve null offset u0 added to the command before the spool (drift of the neutral)"},
        {"valve_deadband",
         {P("delta", "V", 0.2, 0.0, 3.0, 0.2, 0.0, true, {0.8})},
         "spool overlap: a dead zone of half-width delta [V of command] about null, seen through the dither"},
        {"sensor_delay",
         {OnChannel(P("tau_theta", "s", 0.002, 0.0, 0.1, 0.005, 0.0, true, {0.01, 0.03}), "theta"),
          OnChannel(P("tau_dp", "s", 0.002, 0.0, 0.1, 0.005, 0.0, true, {0.03}), "dp"), FormIndex()},
         "the theta and dp transducers each late by their group delay tau (inside the loop and in the record), in "
         "the form that fits best: a pure delay, a first-order lag or a Bessel or Butterworth filter of order 2-4",
         sensor_form_names()},
    };
  }
  std::map<std::string, double> constants() const override { return {{"dither_phase_rad", dither_phase_}}; }
  std::string replay() const override {
    return "closed-loop replay: theta_d through the rig's P+V+dP controller (rt/pvp_controller; " + source_ +
           ") and the reduced pneumatic plant (valve, differential chamber pressure, rotor), controller at the run's "
           "period with the command held, " + std::to_string(kSubsteps) +
           " semi-implicit sub-steps per period; the valve dither is kept, averaged over its phase (mean flow and "
           "50 Hz pressure ripple in closed form, dither phase " + std::to_string(dither_phase_) + " rad " +
           dither_phase_source_ + ")";
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
    for (auto& v : torque) v /= th[kAlpha];
    return torque;
  }

 private:
  // The chambers' differential pressure dp and the gas temperature
  // difference vth between them (the thermal state of polytropic_exponent;
  // both sums stay at their start, as the pressure sum does, docs above).
  struct Gas {
    double gas0, mot0, C2, n, hA, V, Pq, T, R;  // R T / V, Pq alpha / V, ...
    // Half a sub-step of the chambers at flow 2 C1 x_o and rotor speed w.
    void advance(double& dp, double& vth, double flow, double w, double h, double alpha) const {
      const double dm = flow - C2 * dp;  // net mass flow into a, out of b [kg/s]
      const double rate = n * (gas0 * dm - 2.0 * mot0 * w) - (kAdiabaticExponent - 1.0) * hA * vth / V;
      if (hA > 0.0) vth += h * T * (rate / Pq + 2.0 * alpha * w / V - R * T * dm / (Pq * V));
      dp += h * rate;
    }
  };

  // The valve's opening for each command computed so far, and which of them
  // acts over a part of a period when the command takes effect t_command
  // after its sample: over [t_k, t_k + f dt) the command of tick k - m - 1,
  // then that of tick k - m (t_command = (m + f) dt). Before the first, the
  // valve at null.
  struct CommandQueue {
    std::vector<HalfWave> opening;
    HalfWave rest;
    std::size_t m = 0;
    double f = 0.0;
    const HalfWave& at(std::size_t k, std::size_t back) const { return k >= back ? opening[k - back] : rest; }
    // Mean of the opening over [t_k + a dt, t_k + b dt), 0 <= a < b <= 1.
    HalfWave mean(std::size_t k, double a, double b) const {
      const double old_share = std::clamp((f - a) / (b - a), 0.0, 1.0);
      const HalfWave& o = at(k, m + 1);
      const HalfWave& c = at(k, m);
      return {old_share * o.mean + (1.0 - old_share) * c.mean,
              old_share * o.fundamental + (1.0 - old_share) * c.fundamental};
    }
  };

  // which: 1 hysteresis torque, 2 Coulomb torque, into *torque per sample.
  // d: the where's signal at places()[place], per sample (null: none).
  void run(const std::vector<double>& th, std::vector<std::vector<double>>& y, std::vector<double>* torque,
           int which = 0, std::size_t place = 0, const std::vector<double>* d = nullptr) const {
    auto added = [&](std::size_t p, std::size_t k) { return d && place == p ? (*d)[k] : 0.0; };
    const double I = th[kI], b = th[kB], C1 = th[kC1], V = th[kV], alpha = th[kAlpha], dither = th[kDither];
    const double hs = th[kHs], te = th[kTe], thr = std::max(th[kThetaR], 1e-4), tc = th[kTc], dts = th[kDTs],
                 u0 = th[kU0], delta = th[kDelta];
    const std::size_t N = t_.size();
    y.assign(2, std::vector<double>(N, 0.0));
    if (torque) torque->assign(N, 0.0);
    const auto& p = p_;
    const Gas gas{p.gas_constant * p.supply_temperature / V,
                  th[kPq] * alpha / V,
                  th[kC2],
                  th[kGasForm] > 0.5 ? th[kN] : kAdiabaticExponent,  // constant_exponent : heat_exchange
                  th[kGasForm] > 0.5 ? 0.0 : th[kHA],
                  V,
                  th[kPq],
                  p.supply_temperature,
                  p.gas_constant};
    const double Lv = p.spool_limit / p.solenoid_gain;
    const double A = p.dither ? dither : 0.0;
    const double A_avg = std::max(A, kMinSmoothingV);
    const double W = 2.0 * kPi * p.dither_frequency;
    auto opening = [&](double u) { return dithered_opening(u + u0, A_avg, std::min(delta, 0.99 * Lv), Lv); };

    // The sensors: sampled t_sample before the tick, each through its own
    // conditioning (sensor_delay). The 50 Hz ripple on dp passes the dp
    // sensor as a sine does (its gain and phase at 50 Hz).
    const double sample_back = th[kTSample] / dt_;
    const SensorForm form = sensor_form_at(th[kSensorFormIndex]);
    SensorFilter sense_theta(form, th[kTauTheta], dt_), sense_dp(form, th[kTauDp], dt_);
    // The ripple's phase in the record is the sum of the dither's, the
    // sampling's and the dp sensor's: a phase read off the record holds all
    // three, so then the sensor and the sampling add no turn of their own
    // (they would count twice: a 10 ms delay turned the ripple by another
    // half period and gained 0.5 pp); only a stated dither phase leaves
    // theirs to the model. The sensor's gain at 50 Hz applies either way.
    const auto dp_response = sense_dp.response(W);
    const double ripple_gain = std::abs(dp_response);
    const double ripple_turn = dither_phase_read_ ? 0.0 : std::arg(dp_response) - W * th[kTSample];
    const double cr = std::cos(ripple_turn), sr = std::sin(ripple_turn);
    // dp ripple of a fundamental F [V] of the opening: 2 n R T/V C1 k F (a sin - W cos) / (W^2 + a^2),
    // a = n R T / V C2 (1 / tau_chamber), its phase turned by the sampling and the sensor.
    auto ripple = [&](std::size_t k, double fundamental) {
      if (!(A > 0.0)) return 0.0;
      const double g = gas.n * gas.gas0, leak = g * gas.C2;
      const double sn = sin_[k] * cr + cos_[k] * sr, cs = cos_[k] * cr - sin_[k] * sr;
      return ripple_gain * 2.0 * g * C1 * p.solenoid_gain / (W * W + leak * leak) * fundamental * (leak * sn - W * cs);
    };

    PvpController ctrl(pvp_);
    ctrl.reset();
    Sample sample{};
    Command cmd{};
    ControllerTerms terms{};

    CommandQueue queue;
    queue.rest = opening(0.0);
    queue.opening.reserve(N);
    const double cmd_periods = th[kTCmd] / dt_;
    queue.m = static_cast<std::size_t>(std::max(0.0, std::floor(cmd_periods)));
    queue.f = cmd_periods - static_cast<double>(queue.m);
    std::vector<double> h_theta(N), h_dp(N), h_fund(N);
    double fund_prev = queue.rest.fundamental;
    // Slow part of dp at the start: the measured mean over one dither period
    // less the modelled ripple's mean there.
    double rip0 = 0.0;
    for (std::size_t i = 0; i < dp0_window_; ++i) rip0 += ripple(i, fund_prev) / static_cast<double>(dp0_window_);
    double theta = theta0_, omega = 0.0, dp = dp0_ - rip0, vth = 0.0, z = 0.0;
    sense_theta.reset(theta);
    sense_dp.reset(dp);
    const double h = dt_ / kSubsteps;
    const bool sign_like = hs + tc + dts > 0.0, dahl = te > 0.0;
    for (std::size_t k = 0; k < N; ++k) {
      h_theta[k] = theta;
      h_dp[k] = dp;
      h_fund[k] = fund_prev;  // the ripple at t_k comes from the opening over the period before it
      const double s = static_cast<double>(k) - sample_back;
      const double theta_m = sense_theta.step(at(h_theta, s)) + added(3, k);
      const double dp_m = sense_dp.step(at(h_dp, s)) + ripple(k, at(h_fund, s - th[kTauDp] / dt_)) + added(4, k);
      y[0][k] = theta_m;
      y[1][k] = dp_m;
      sample.value[0] = theta_m;
      sample.value[1] = dp_m;
      ctrl.update(theta_d_[k], sample, cmd, terms);
      queue.opening.push_back(opening(cmd.value[0] + added(2, k)));
      fund_prev = A > 0.0 ? queue.mean(k, 0.0, 1.0).fundamental : 0.0;
      const double torque_in = added(0, k), rate_in = added(1, k);
      // Each sub-step is split symmetrically (Strang): half a step of the
      // chambers, the rotor over the whole step, the other half of the
      // chambers with the new speed; the angle and the Dahl travel use the
      // mean speed. Second order, so the sub-step leaves no O(h) time shift
      // between angle and pressure that would pass for a sensor delay.
      for (int j = 0; j < kSubsteps; ++j) {
        const double a = static_cast<double>(j) / kSubsteps, e = static_cast<double>(j + 1) / kSubsteps;
        const double flow = 2.0 * C1 * p.solenoid_gain * queue.mean(k, a, e).mean;  // 2 C1 x_o [kg/s]
        gas.advance(dp, vth, flow, omega, 0.5 * h, alpha);
        dp += 0.5 * h * rate_in;
        const double S = hs + tc + dts * std::exp(-(omega / kStribeckSpeed) * (omega / kStribeckSpeed));
        const double th_ = sign_like ? std::tanh(omega / kEps) : 0.0;
        const double T = alpha * dp - te * z + stop_torque(theta + 0.5 * h * omega, omega) + torque_in;
        // Semi-implicit in omega for the stiff tanh and the viscous term.
        const double slope = S / kEps * (1.0 - th_ * th_) + b;
        const double wn = omega + h * (T - S * th_ - b * omega) / (I + h * slope);
        const double wm = 0.5 * (omega + wn);
        theta += h * wm;
        if (dahl) {  // exact for the mean speed over the sub-step
          const double da = wm * std::tanh(wm / kEps) / thr * h;  // >= 0
          const double ex = std::exp(-da);
          z = z * ex + (wm * h / thr) * (da > 1e-12 ? (1.0 - ex) / da : 1.0 - 0.5 * da);
        }
        gas.advance(dp, vth, flow, wn, 0.5 * h, alpha);
        dp += 0.5 * h * rate_in;
        omega = wn;
      }
      if (torque) {
        const double sg = std::tanh(omega / kEps);
        (*torque)[k] = which == 2 ? (tc + dts * std::exp(-(omega / kStribeckSpeed) * (omega / kStribeckSpeed))) * sg
                                  : hs * sg + te * z;
      }
      if (!std::isfinite(theta) || !std::isfinite(dp)) {
        for (std::size_t jj = k; jj < N; ++jj) y[0][jj] = 1e3, y[1][jj] = 1e9;
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

  // The dither phase at which the baseline's ripple (phase = dither phase
  // - atan2(W, a), a = 1.4 R T / V C2 the chambers' pole, docs above) has
  // the phase of the 50 Hz component of the measured dp: a lock-in over the
  // whole record, dp less its mean over one dither period. A record whose
  // ripple does not stand out of the noise (less than 4 standard errors of
  // the lock-in) keeps phase 0, the simulator's and a DAC's convention.
  double dither_phase_from_ripple(double W) const {
    const auto& dp = outputs_[1].measured;
    const auto per = static_cast<std::size_t>(std::lround(1.0 / (p_.dither_frequency * dt_)));
    if (per < 3 || dp.size() < 4 * per) return 0.0;
    const auto mean = moving_mean(dp, per);
    double s = 0.0, c = 0.0, ss = 0.0;
    std::size_t n = 0;
    for (std::size_t i = per; i < dp.size(); ++i) {
      const double hp = dp[i] - mean[i];  // the window ends at i: its 50 Hz content is zero, its delay irrelevant
      s += hp * std::sin(W * t_[i]);
      c += hp * std::cos(W * t_[i]);
      ss += hp * hp;
      ++n;
    }
    const double amp = 2.0 * std::hypot(s, c) / static_cast<double>(n);
    const double se = 2.0 * std::sqrt(ss / static_cast<double>(n)) / std::sqrt(static_cast<double>(n));
    if (!(amp > 4.0 * se)) return 0.0;
    const double pole = kAdiabaticExponent * p_.gas_constant * p_.supply_temperature / p_.chamber_volume *
                        p_.flow_pressure_coefficient;
    return std::atan2(c, s) + std::atan2(W, pole);
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
  std::string dither_phase_source_;
  bool dither_phase_read_ = false;  // off the record's ripple, sensor and sampling included
  std::size_t dp0_window_ = 1;
  std::vector<Output> outputs_;
};

}  // namespace

std::unique_ptr<RigModel> make_pneumatic_rotary_model(const RunFile& run, const RigModelOptions& options) {
  return std::make_unique<PneumaticRotaryModel>(run, options);
}

}  // namespace rigctl::diag
