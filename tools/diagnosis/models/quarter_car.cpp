// Diagnosis sub-model of seed 000's quarter-car rig: two sub-models replayed
// side by side in one parameter vector.
//  * Actuator (closed-loop replay): the measured demand x_ref through the
//    rig's own PI controller (rt/pi_controller) and the servovalve/actuator
//    equations (spool lag, orifice flows of plant/servo_valve, chamber
//    pressures, rod), loaded by the tyre over the measured wheel motion.
//    Outputs u, x_r and, where recorded, p1 and p2. Causes:
//    actuator_seal_friction, cross_port_leakage, valve_deadband, entrained_air.
//  * Suspension (open-loop replay): the measured x_r drives wheel and body.
//    Outputs x_b, x_w and, where recorded, the tyre load f_t. Causes:
//    bearing_friction, damper_asymmetry, sensor_offset, tyre_liftoff.
// An effect of one sub-model leaves the other's outputs unchanged, so the
// engine's per-signal gain points at the right place; the exceptions are
// tyre lift-off (the tyre is in both), an offset on the x_w transducer (the
// actuator's tyre load is driven by the measured x_w) and the sensors
// (sensor_delay): x_r's is the controller's feedback, inside the actuator's
// loop, and both sub-models are driven by a measured position (x_r, x_w),
// which a late sensor shows late; the replay drives them with the measured
// input advanced by its sensor's group delay.
#include <algorithm>
#include <cmath>
#include <mutex>

#include "config/rig_config.hpp"
#include "plant/quarter_car/bearing_friction.hpp"
#include "plant/quarter_car/hidden_effect_laws.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "plant/servo_valve.hpp"
#include "rt/control/pi_controller.hpp"
#include "tools/diagnosis/models/controller_from_record.hpp"
#include "tools/diagnosis/rigs.hpp"
#include "tools/diagnosis/sensor_filter.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {

namespace {

std::string fmt_bar(double pa) { return std::to_string(static_cast<long>(std::lround(pa / 1e5))); }

// The entrained-air candidate's bubbles: a polytropic index between
// isothermal (1, slow compression) and adiabatic (1.4, fast). A constant
// bulk-modulus ratio, the candidate before, could not follow a run whose
// air (isothermal bubbles, weak) makes the modulus fall steeply toward low
// pressure: 0.23 pp on p2, `unexplained` at 7 x its noise.
constexpr double kBubbleIndex = 1.2;

// Below this pressure difference the orifice leak of cross_port_leakage is
// taken as laminar (its sqrt has an infinite slope at 0, which the fit's
// derivatives and the RK4 step cannot take); 1 bar is about 2 % of the rig's
// load pressures.
constexpr double kOrificeTransition = 1e5;  // [Pa]

// Smooth max(0, x) with a corner of width eps (softplus): the fitted
// candidates are smooth where the generating physics is sharp.
double softplus(double x, double eps) {
  const double z = x / eps;
  return z > 30.0 ? x : eps * std::log1p(std::exp(z));
}

// Tyre contact force with the fitted lift-off blend: bilateral at uni = 0,
// a contact that cannot pull at uni = 1 (smooth over ~20 N).
double tyre_contact(double f_total, double uni) {
  return uni > 0.0 ? f_total + uni * softplus(-f_total, 20.0) : f_total;
}

// The causes of the suspension sub-model alone (tyre lift-off and the
// sensors act in both; the rest are the actuator's).
bool suspension_cause(const std::string& cause) {
  return cause == "bearing_friction" || cause == "damper_asymmetry";
}

// Parameter indices (baseline, then effects in effects() order).
enum : std::size_t {
  kKs, kBd, kMb, kMw, kKt, kBt,  // baseline: suspension and tyre
  kKv, kTauR, kBetaNom, kRl, kPs, kA1, kA2, kBvr, kVd,  // baseline: valve and actuator
  kFc, kDFs, kD, kMu,            // bearing_friction
  kDc,                           // damper_asymmetry
  kTauXr, kTauXb, kTauXw, kSensorForm,  // sensor_delay
  kBb, kBw,                      // sensor_offset
  kUni,                          // tyre_liftoff
  kSealFm, kSealPc,              // actuator_seal_friction
  kLeak, kLeakOrifice,           // cross_port_leakage
  kDead,                         // valve_deadband
  kAirFraction,                  // entrained_air
  kParamCount
};

// Where an effect can enter (RigModel::places, docs/diagnosis.md 3): the
// signal the "where" adds in simulate_with_input.
enum PlaceIndex : std::size_t {
  kOnBody, kOnWheel, kInSuspension,             // suspension sub-model: forces [N]
  kOnRod, kOnSpool, kCrossPort, kIntoChamber1, kIntoChamber2,  // actuator: force, spool, flows
  kSensorXr, kSensorXw,                          // sensors the model itself reads (in the loop, tyre input)
  kModelPlaces
};
// What a place adds, per sample (Injection) and inside a sub-step (Extra).
struct Injection {
  std::size_t place;
  const std::vector<double>* d;
  double at(std::size_t p, std::size_t i) const { return place == p ? (*d)[i] : 0.0; }
};
struct Extra {
  double rod = 0.0, spool = 0.0, cross = 0.0, q1 = 0.0, q2 = 0.0;
};

constexpr std::size_t kSuspensionParams[] = {kKs,  kBd,    kMb,    kMw,    kKt,         kBt, kFc, kDFs, kD,  kMu,
                                             kDc, kTauXr, kTauXb, kTauXw, kSensorForm, kBb, kBw, kUni};
constexpr std::size_t kActuatorParams[] = {kMb,  kMw,     kKt,     kBt,   kKv,   kTauR,        kBetaNom, kRl,
                                           kPs,  kA1,     kA2,     kBvr,  kVd,   kUni,         kSealFm,  kSealPc,
                                           kLeak, kLeakOrifice, kDead, kAirFraction, kBw, kTauXr, kTauXw, kSensorForm};

template <std::size_t N>
std::vector<double> key(const std::vector<double>& th, const std::size_t (&idx)[N]) {
  std::vector<double> k;
  k.reserve(N);
  for (auto i : idx) k.push_back(th[i]);
  return k;
}

// Recent sub-model replays by parameter values (thread-safe: the fit's
// Jacobian columns run on two threads). A Jacobian column that moves an
// actuator parameter needs the suspension replay of the column's base point,
// and the other way round; the base must still be here after the columns
// before it have added theirs. With 4 entries it was not (a round-2 refit
// moves 20 parameters): the quarter car replayed the actuator 8252 times in
// one diagnosis instead of 4914. kCapacity covers the central differences
// of the largest fit (2 x ~24 columns) and the trial points around them;
// at 6649 samples an entry is 0.1-0.2 MB, so the cache stays under 15 MB.
class ReplayCache {
 public:
  bool find(const std::vector<double>& key, std::vector<std::vector<double>>& out) const {
    std::lock_guard<std::mutex> lock(m_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->first == key) {
        out = it->second;
        if (it != entries_.begin()) std::iter_swap(it, entries_.begin());
        return true;
      }
    }
    return false;
  }
  void put(std::vector<double> key, std::vector<std::vector<double>> y) const {
    std::lock_guard<std::mutex> lock(m_);
    entries_.emplace(entries_.begin(), std::move(key), std::move(y));
    if (entries_.size() > kCapacity) entries_.pop_back();
  }

 private:
  static constexpr std::size_t kCapacity = 64;
  mutable std::mutex m_;
  mutable std::vector<std::pair<std::vector<double>, std::vector<std::vector<double>>>> entries_;
};

class QuarterCarModel : public RigModel {
 public:
  QuarterCarModel(const RunFile& run, const RigModelOptions& o) : t_(run.t), dt_(run.dt) {
    if (!o.config_path.empty()) {
      const auto cfg = load_replay_config(o.config_path, RigKind::kQuarterCar);
      p_ = cfg.quarter_car;
      pi_ = cfg.controller.pi;
    }
    pi_.period_s = dt_;
    controller_source_ = calibrate_pi(pi_, run.col("x_ref"), run.col("x_r"), run.col("u"));
    pi_.feedback_input = 0;
    pi_.output_index = 0;
    xref_ = run.col("x_ref");
    xr_ = run.col("x_r");
    vr_ = central_diff(xr_, dt_);
    xw_ = run.col("x_w");
    vb_ = run.has("v_b") ? run.col("v_b") : central_diff(run.col("x_b"), dt_);
    vw_ = run.has("v_w") ? run.col("v_w") : central_diff(xw_, dt_);
    outputs_ = {{"x_b", run.col("x_b")}, {"x_w", xw_}, {"u", run.col("u")}, {"x_r", xr_}};
    if (run.has("p1") && run.has("p2")) {
      outputs_.push_back({"p1", run.col("p1")});
      outputs_.push_back({"p2", run.col("p2")});
    }
    act_outputs_ = outputs_.size() - 2;
    seal_sum_ = p_.supply_pressure;  // without pressures: the symmetric valve's rest, p1 + p2 = Ps
    if (act_outputs_ > 2) {
      const auto &p1 = outputs_[4].measured, &p2 = outputs_[5].measured;
      double sum = 0.0;
      for (std::size_t i = 0; i < p1.size(); ++i) sum += p1[i] + p2[i];
      seal_sum_ = sum / static_cast<double>(std::max<std::size_t>(1, p1.size()));
    }
    // The tyre load cell, where the run has one, is an output of the
    // suspension replay: a lift-off clips it at zero where the bilateral
    // tyre pulls, which the positions show only faintly (a weak lift-off
    // gains 0.1-0.4 pp on p1, and nothing on x_w).
    if (run.has("f_t")) {
      ft_ = run.col("f_t");
      outputs_.push_back({"f_t", ft_});
      // The tyre's damping force on the load cell takes the rod velocity
      // over +-2 samples: the +-1 difference of a 20 um LVDT is 5.7 mm/s of
      // noise, 22 N through the tyre's 3.9 kN s/m, more than the load cell's
      // own; over +-2 it is half that, and a 10 Hz wheel hop loses 1.6 %.
      vr_load_.assign(xr_.size(), 0.0);
      for (std::size_t i = 2; i + 2 < xr_.size(); ++i) vr_load_[i] = (xr_[i + 2] - xr_[i - 2]) / (4.0 * dt_);
    }
  }
  RunFileRig rig() const override { return RunFileRig::kQuarterCar; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }
  std::vector<ParamSpec> baseline() const override {
    // Every parameter a real rig is uncertain about, each with a prior of its
    // tolerance: 5 % for masses, stiffnesses, areas, volumes, supply and bulk
    // modulus (catalogue and drawing values); 10 % for damping, the valve's
    // gain and time constant and the leakage (worn parts, data sheets).
    // Far below its band, the leakage resistance is a worn seal and the bulk
    // modulus aerated oil: those moves are the causes' (ParamSpec::stands_for).
    const auto& p = p_;
    return {Prior("ks", "N/m", p.spring_stiffness, 0.05),       Prior("bd", "N s/m", p.damper_damping, 0.10),
            Prior("Mb", "kg", p.mass_body, 0.05),                Prior("Mw", "kg", p.mass_wheel, 0.05),
            Prior("kt", "N/m", p.tyre_stiffness, 0.05),          Prior("bt", "N s/m", p.tyre_damping, 0.10),
            Prior("kv_scale", "1", 1.0, 0.10),                   Prior("tau_r", "s", p.valve_time_constant, 0.10),
            StandsFor(Prior("beta", "Pa", p.bulk_modulus, 0.05), "entrained_air", -1),
            StandsFor(Prior("R_l", "Pa s/m^3", p.leakage_resistance, 0.10), "cross_port_leakage", -1),
            Prior("Ps", "Pa", p.supply_pressure, 0.05),          Prior("A1", "m^2", p.area_cap, 0.05),
            Prior("A2", "m^2", p.area_rod, 0.05),                Prior("Bvr", "N s/m", p.rod_damping, 0.10),
            Prior("V_dead", "m^3", p.dead_volume_cap, 0.05)};
    // No loop-timing parameters here (the pneumatic rig has them): with
    // t_command and t_sample in the actuator's loop the quarter car's fits
    // ran to their iteration limits (calibration 5 + 6 iterations became
    // 22 + 21, a devset diagnosis 26 s of CPU became 134 s), and the
    // development set's quarter-car clean runs need none.
  }
  std::vector<EffectSpec> effects() const override {
    return {
        {"bearing_friction",
         // Any of the four beyond 3 sigma makes the friction significant: with a
         // normal-force dependent truth the fit may carry the Coulomb level in mu.
         {P("Fc", "N", 20.0, 0.0, 1e4, 20.0, 0.0, true), P("dFs", "N", 0.0, 0.0, 1e4, 20.0, 0.0, true),
          P("D", "N s/m", 0.0, 0.0, 1e5, 100.0, 0.0, true), P("mu", "1", 0.0, 0.0, 5.0, 0.05, 0.0, true)},
         "body linear-bearing friction: Coulomb Fc + mu F_n (normal force of the inclined spring-damper), "
         "stiction excess dFs with a Stribeck decay (v_s 15 mm/s), viscous D, on the absolute body velocity"},
        {"damper_asymmetry", {P("dc", "N s/m", 0.0, -1e5, 1e5, 100.0, 0.0, true)},
         "rebound and compression damping differ: bd + dc tanh(v_rel / 0.01 m/s)"},
        {"sensor_delay",
         {OnChannel(P("tau_x_r", "s", 0.002, 0.0, 0.1, 0.002, 0.0, true, {0.01}), "x_r"),
          OnChannel(P("tau_x_b", "s", 0.002, 0.0, 0.1, 0.002, 0.0, true, {0.01}), "x_b"),
          OnChannel(P("tau_x_w", "s", 0.002, 0.0, 0.1, 0.002, 0.0, true), "x_w"), FormIndex()},
         "the x_r (the controller's feedback), x_b and x_w transducers each late by their group delay tau, in the "
         "form that fits best: a pure delay, a first-order lag or a Bessel or Butterworth filter of order 2-4",
         sensor_form_names()},
        {"sensor_offset",
         {P("b_b", "m", 0.0, -0.1, 0.1, 1e-3, 0.0, true), P("b_w", "m", 0.0, -0.1, 0.1, 1e-3, 0.0, true)},
         "constant offsets on the x_b and x_w transducers"},
        {"tyre_liftoff", {P("unilateral", "1", 0.5, 0.0, 1.0, 1.0, 0.0, true)},
         "the tyre cannot pull: contact force F + unilateral softplus(-F) (smooth over 20 N)"},
        // The level at the run's mean pressure sum and its slope, not the
        // preload and the slope: over one run's narrow band of p1 + p2 the
        // preload and the slope trade against each other, so neither was 3
        // sigma from 0 beside bearing friction (2.1 pp on p1), though the
        // level they make together is.
        {"actuator_seal_friction",
         {P("F_m", "N", 50.0, 0.0, 2000.0, 50.0, 0.0, true), P("f_c", "N/Pa", 0.0, 0.0, 1e-4, 2e-6, 0.0, true)},
         "rod seal friction: Coulomb (F_m + f_c (p1 + p2 - " + fmt_bar(seal_sum_) +
             " bar, the run's mean)) sign(v_r) on the actuator, stick-capable"},
        {"cross_port_leakage",
         {P("C_il", "m^3/(s Pa)", 2e-12, 0.0, 1e-9, 4e-12, 0.0, true),
          P("C_t", "m^3/(s Pa^0.5)", 0.0, 0.0, 1e-6, 5e-9, 0.0, true)},
         "extra cross-port leakage beside the nominal one, laminar C_il (p1 - p2) and through an orifice "
         "(turbulent) C_t sign(p1 - p2) sqrt|p1 - p2|"},
        {"valve_deadband", {P("delta", "1", 0.01, 0.0, 0.3, 0.01, 0.0, true, {0.04})},
         "spool overlap: metering edge x_s - delta (softplus-smoothed dead zone over +-delta)"},
        {"entrained_air", {P("alpha", "1", 0.02, 0.0, 0.5, 0.02, 0.0, true, {0.1})},
         "free air in the oil: volume fraction alpha at atmospheric pressure, a bulk modulus falling with the "
         "chamber's pressure (mixture law, bubble index 1.2)"},
    };
  }
  // Suspension causes move only the suspension's parameters (the tyre and
  // masses are in both); actuator causes only the actuator's; lift-off and
  // the sensors both (an offset on x_w is also in the actuator's
  // wheel input, so the actuator's calibration may have bent to it).
  bool couples(std::size_t index, const std::string& cause) const override {
    const bool suspension_param = index <= kBt;
    const bool shared = index >= kMb && index <= kBt;
    if (suspension_cause(cause)) return suspension_param;
    if (cause == "tyre_liftoff" || cause == "sensor_offset" || cause == "sensor_delay") return true;
    return !suspension_param || shared;
  }
  std::map<std::string, double> constants() const override {
    return {{"P_m", seal_sum_}, {"air_bubble_index", kBubbleIndex}};
  }
  std::vector<std::size_t> acts_on(const std::string& cause) const override {
    if (cause == "tyre_liftoff" || cause == "sensor_offset" || cause == "sensor_delay") return {};  // both sub-models
    const std::size_t ft = 2 + act_outputs_;
    if (suspension_cause(cause)) {
      if (ft_.empty()) return {0, 1};
      return {0, 1, ft};
    }
    std::vector<std::size_t> act;
    for (std::size_t o = 2; o < ft; ++o) act.push_back(o);
    return act;
  }
  std::string replay() const override {
    return "two sub-models: the actuator by closed-loop replay (x_ref through the rig's PI controller, servovalve "
           "and actuator, 5 RK4 sub-steps per period, tyre load over the measured wheel motion: outputs u, x_r, p1, "
           "p2; the seal friction applied implicitly after each sub-step) and the suspension by open-loop replay "
           "(measured x_r drives wheel and body, 8 sub-steps, implicit stick-capable bearing friction: outputs x_b, "
           "x_w and, where recorded, the tyre load f_t); " + controller_source_;
  }
  // The two sub-models share only `unilateral`; a fit that moves one
  // sub-model's parameters (a column of the central differences, say) takes
  // the other's outputs from a small cache instead of replaying it again.
  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    simulate_prefix(th, y, t_.size());
  }
  void simulate_prefix(const std::vector<double>& th, std::vector<std::vector<double>>& y,
                       std::size_t samples) const override {
    samples = std::min(samples, t_.size());
    y.assign(outputs_.size(), std::vector<double>(t_.size()));
    std::vector<double> ks = key(th, kSuspensionParams), ka = key(th, kActuatorParams);
    ks.push_back(static_cast<double>(samples));  // a prefix is not the whole replay
    ka.push_back(static_cast<double>(samples));
    std::vector<std::vector<double>> part;
    const std::size_t ft = 2 + act_outputs_;  // f_t's index, if recorded
    const bool has_ft = !ft_.empty();
    if (susp_cache_.find(ks, part)) {
      y[0] = std::move(part[0]);
      y[1] = std::move(part[1]);
      if (has_ft) y[ft] = std::move(part[2]);
    } else {
      simulate_suspension(th, y[0], y[1], has_ft ? &y[ft] : nullptr, samples);
      if (has_ft) susp_cache_.put(ks, {y[0], y[1], y[ft]});
      else susp_cache_.put(ks, {y[0], y[1]});
    }
    if (act_cache_.find(ka, part)) {
      for (std::size_t o = 0; o < act_outputs_; ++o) y[2 + o] = std::move(part[o]);
    } else {
      simulate_actuator(th, y, samples);
      const auto first = y.begin() + 2;
      act_cache_.put(ka, std::vector<std::vector<double>>(first, first + static_cast<std::ptrdiff_t>(act_outputs_)));
    }
  }
  std::vector<Place> places() const override {
    // Steps of the linearisation: a few per mille of the signals there
    // (body forces of hundreds of N, flows of 1e-5 m^3/s, a spool of 1).
    std::vector<Place> p = {
        {"a force on the body", "N", 1.0, -1, false, {"bearing_friction"}},
        {"a force on the wheel", "N", 1.0, -1, false, {"tyre_liftoff"}},
        {"a force between wheel and body (the suspension)", "N", 1.0, -1, false, {"damper_asymmetry"}},
        {"a force on the rod", "N", 1.0, -1, false, {"actuator_seal_friction"}},
        {"an error of the spool position (valve opening)", "1", 1e-4, -1, false, {"valve_deadband"}},
        {"a flow from chamber 1 to chamber 2", "m^3/s", 1e-8, -1, false, {"cross_port_leakage"}},
        {"a flow into chamber 1", "m^3/s", 1e-8, -1, false, {"entrained_air", "cross_port_leakage", "valve_deadband"}},
        {"a flow into chamber 2", "m^3/s", 1e-8, -1, false, {"entrained_air", "cross_port_leakage", "valve_deadband"}},
        {"an error on the x_r sensor (the feedback)", "m", 1e-5, 3, true, {"sensor_delay", "sensor_offset"}},
        {"an error on the x_w sensor (also the tyre's input)", "m", 1e-5, 1, true, {"sensor_delay", "sensor_offset"}},
        {"an error on the x_b sensor", "m", 1e-5, 0, false, {"sensor_delay", "sensor_offset"}}};
    if (act_outputs_ > 2) {
      p.push_back({"an error on the p1 sensor", "Pa", 1e3, 4, false, {}});
      p.push_back({"an error on the p2 sensor", "Pa", 1e3, 5, false, {}});
    }
    if (!ft_.empty())
      p.push_back({"an error on the f_t sensor", "N", 1.0, static_cast<int>(2 + act_outputs_), false, {"tyre_liftoff"}});
    return p;
  }
  std::vector<Feature> features() const override {
    std::vector<double> rel(vw_.size()), spring(vw_.size()), tyre(vw_.size());
    for (std::size_t i = 0; i < rel.size(); ++i) {
      rel[i] = vw_[i] - vb_[i];
      spring[i] = xw_[i] - outputs_[0].measured[i];
      tyre[i] = xr_[i] - xw_[i];
    }
    // Outputs: x_b 0, x_w 1, u 2, x_r 3, p1 4, p2 5 (Feature::from).
    std::vector<Feature> f = {{"v_b", FeatureKind::kVelocity, vb_, {0}},
                              {"v_w", FeatureKind::kVelocity, vw_, {1}},
                              {"v_w - v_b", FeatureKind::kVelocity, rel, {0, 1}},
                              {"v_r", FeatureKind::kVelocity, vr_, {3}},
                              {"u", FeatureKind::kCommand, outputs_[2].measured, {2, 3}},  // PI of x_r
                              {"x_b", FeatureKind::kPosition, outputs_[0].measured, {0}},
                              {"x_r", FeatureKind::kPosition, xr_, {3}},
                              {"x_w - x_b", FeatureKind::kValue, spring, {0, 1}},
                              {"x_r - x_w", FeatureKind::kValue, tyre, {1, 3}}};
    if (act_outputs_ > 2) {
      const auto &p1 = outputs_[4].measured, &p2 = outputs_[5].measured;
      std::vector<double> dp(p1.size());
      for (std::size_t i = 0; i < dp.size(); ++i) dp[i] = p1[i] - p2[i];
      f.push_back({"p1", FeatureKind::kValue, p1, {4}});
      f.push_back({"p2", FeatureKind::kValue, p2, {5}});
      f.push_back({"p1 - p2", FeatureKind::kValue, dp, {4, 5}});
      f.push_back({"dp1/dt", FeatureKind::kValue, smooth_rate(p1), {4}});
      f.push_back({"dp2/dt", FeatureKind::kValue, smooth_rate(p2), {5}});
    }
    return f;
  }
  void simulate_with_input(const std::vector<double>& th, std::size_t place, const std::vector<double>& d,
                           std::vector<std::vector<double>>& y) const override {
    simulate(th, y);  // the calibrated replay (from the cache), then the sub-model the place is in again
    const Injection in{place, &d};
    const bool suspension = place == kOnBody || place == kOnWheel || place == kInSuspension || place == kSensorXw;
    const bool actuator = !suspension || place == kSensorXw;
    const std::size_t ft = 2 + act_outputs_;
    if (suspension) simulate_suspension(th, y[0], y[1], ft_.empty() ? nullptr : &y[ft], t_.size(), &in);
    if (actuator) simulate_actuator(th, y, t_.size(), &in);
  }
  Indicator indicator(const std::string& cause) const override {
    if (cause == "damper_asymmetry") {
      std::vector<double> r(vw_.size());
      for (std::size_t i = 0; i < r.size(); ++i) r[i] = vw_[i] - vb_[i];
      return {"v_w - v_b [m/s]", r};
    }
    if (cause == "actuator_seal_friction") return {"rod velocity v_r [m/s]", vr_};
    if (cause == "valve_deadband" || cause == "cross_port_leakage") return {"valve command u [1]", outputs_[2].measured};
    if (cause == "entrained_air") return {"x_r [m]", xr_};
    if (cause == "tyre_liftoff") {
      // Lift-off happens where the tyre load reaches 0: the measured load
      // cell where the run has one, else the tyre's deflection.
      if (!ft_.empty()) return {"tyre load f_t [N]", ft_};
      std::vector<double> d(xr_.size());
      for (std::size_t i = 0; i < d.size(); ++i) d[i] = xr_[i] - xw_[i];
      return {"tyre deflection x_r - x_w [m]", d};
    }
    return {"body velocity v_b [m/s]", vb_};
  }
  std::vector<double> effect_term(const std::string& cause, const std::vector<double>& th) const override {
    if (cause != "bearing_friction") return {};
    // Sliding friction against the measured body velocity, divided by ks so
    // it shares the x_b residual's axis (a displacement).
    std::vector<double> f(vb_.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double v = vb_[i];
      const double sgn = v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
      f[i] = (sgn * (th[kFc] + th[kDFs] * std::exp(-(v / 0.015) * (v / 0.015))) + th[kD] * v) / th[kKs];
    }
    return f;
  }

 private:
  // yf: the tyre load (static part included), where the run has it.
  // The rate of a noisy pressure over +-4 samples (20 ms): the +-1
  // difference of a 0.2 bar transducer is 57 bar/s of noise.
  std::vector<double> smooth_rate(const std::vector<double>& p) const {
    std::vector<double> r(p.size(), 0.0);
    for (std::size_t i = 4; i + 4 < p.size(); ++i) r[i] = (p[i + 4] - p[i - 4]) / (8.0 * dt_);
    return r;
  }

  // yf: the tyre load (static part included), where the run has it. `in`:
  // the where's signal at a suspension place (RigModel::simulate_with_input).
  void simulate_suspension(const std::vector<double>& th, std::vector<double>& yb, std::vector<double>& yw,
                           std::vector<double>* yf, std::size_t samples, const Injection* in = nullptr) const {
    const double ks = th[kKs], bd = th[kBd], Fc = th[kFc], dFs = th[kDFs], D = th[kD], mu = th[kMu], dc = th[kDc],
                 b_b = th[kBb], b_w = th[kBw], uni = th[kUni];
    // The measured x_r drives the wheel: a late x_r sensor shows the road
    // late, so the replay takes it advanced by the sensor's group delay.
    const std::vector<double> xr_in = advanced(xr_, th[kTauXr]);
    const std::size_t n = t_.size();
    const int sub = 8;
    const double h = dt_ / sub;
    const double mw = th[kMw], mb = th[kMb], kt = th[kKt], bt = th[kBt];
    const double f0 = (mb + mw) * p_.gravity, weight = mb * p_.gravity;
    const bool friction = Fc > 0.0 || dFs > 0.0 || D > 0.0 || mu > 0.0;
    const BearingFrictionParams bp = p_.bearing_friction;
    double xw = xw_[0], xb = outputs_[0].measured[0], vw = vw_[0], vb = friction ? 0.0 : vb_[0];
    for (std::size_t i = 0; i < samples; ++i) {
      const double f_body = in ? in->at(kOnBody, i) : 0.0, f_wheel = in ? in->at(kOnWheel, i) : 0.0,
                   f_susp = in ? in->at(kInSuspension, i) : 0.0;
      yb[i] = xb + b_b;
      yw[i] = xw + b_w + (in ? in->at(kSensorXw, i) : 0.0);
      const double xr0 = xr_in[i], xr1 = i + 1 < n ? xr_in[i + 1] : xr_in[i];
      const double vr = (xr1 - xr0) / dt_;
      if (yf) (*yf)[i] = tyre_contact(f0 + kt * (xr0 - xw) + bt * (vr_load_[i] - vw), uni);
      for (int s = 0; s < sub; ++s) {
        const double xr = xr0 + (xr1 - xr0) * (s + 0.5) / sub;
        const double vrel = vw - vb;
        const double fs = ks * (xw - xb) + (dc != 0.0 ? bd + dc * std::tanh(vrel / 0.01) : bd) * vrel + f_susp;
        const double ft = tyre_contact(f0 + kt * (xr - xw) + bt * (vr - vw), uni) - f0;  // static part removed
        vw += h * (ft - fs + f_wheel) / mw;
        xw += h * vw;
        if (friction) {
          double cn = Fc;
          if (mu > 0.0) cn += mu * bearing_friction_levels(bp, weight, fs, xw - xb).normal;
          const double c = cn + dFs * (vb == 0.0 ? 1.0 : std::exp(-(vb / 0.015) * (vb / 0.015)));
          vb = implicit_velocity(mb, vb, fs + f_body, h, c, c, D, D);
        } else {
          vb += h * (fs + f_body) / mb;
        }
        xb += h * vb;
      }
      if (!std::isfinite(xb) || !std::isfinite(xw)) {
        for (std::size_t j = i; j < n; ++j) yb[j] = yw[j] = 1e3;
        if (yf) std::fill(yf->begin() + static_cast<std::ptrdiff_t>(i), yf->end(), 1e9);
        return;
      }
    }
    const SensorForm form = sensor_form_at(th[kSensorForm]);
    SensorFilter(form, th[kTauXb], dt_).apply(yb);
    SensorFilter(form, th[kTauXw], dt_).apply(yw);
  }

  // x advanced by tau [s] (the value tau later; the last value held): the
  // true signal under a sensor of that group delay, to its low-frequency
  // order. Unchanged for tau = 0.
  std::vector<double> advanced(const std::vector<double>& x, double tau) const {
    if (!(tau > 0.0)) return x;
    std::vector<double> out(x.size());
    const double shift = tau / dt_;
    for (std::size_t i = 0; i < x.size(); ++i) out[i] = at(x, static_cast<double>(i) + shift);
    return out;
  }

  // State of the actuator replay: spool, chamber pressures, rod.
  struct Act {
    double xs, p1, p2, xr, vr;
  };

  void actuator_derivatives(const std::vector<double>& th, const Act& a, double u, double xw, double vw, Act& d,
                            const Extra& x = {}) const {
    const auto& p = p_;
    d.xs = (u - a.xs) / th[kTauR];
    const double delta = th[kDead];
    // Overlapped spool: the metering edge opens delta later on either side.
    const double xs = a.xs + x.spool;
    const double spool = delta > 0.0 ? softplus(xs - delta, 0.002) - softplus(-xs - delta, 0.002) : xs;
    const ValveFlows q = valve_flows(spool, a.p1, a.p2, p.valve_flow_gain * th[kKv], th[kPs], p.laminar_pressure);
    const double dpl = a.p1 - a.p2;
    // A worn seal leaks laminar (C_il dp) and through an orifice (C_t
    // sign(dp) sqrt(|dp|), turbulent), smoothed to laminar below
    // kOrificeTransition so its slope stays finite at dp = 0.
    const double q_orifice =
        th[kLeakOrifice] != 0.0
            ? th[kLeakOrifice] * dpl / std::sqrt(std::sqrt(dpl * dpl + kOrificeTransition * kOrificeTransition))
            : 0.0;
    const double q_leak = (p.leakage ? dpl / th[kRl] : 0.0) + th[kLeak] * dpl + q_orifice + x.cross;
    // Free air: a bulk modulus that falls with the chamber's pressure
    // (kBubbleIndex: bubbles between isothermal and adiabatic).
    const double alpha = th[kAirFraction], beta_oil = th[kBetaNom];
    const double beta1 = alpha > 0.0 ? mixture_bulk_modulus(beta_oil, alpha, kBubbleIndex, a.p1) : beta_oil;
    const double beta2 = alpha > 0.0 ? mixture_bulk_modulus(beta_oil, alpha, kBubbleIndex, a.p2) : beta_oil;
    const double a1 = th[kA1], a2 = th[kA2];
    const double v1 = std::max(th[kVd] + a1 * (a.xr - p.stroke_min), 1e-9);
    const double v2 = std::max(th[kVd] * p.dead_volume_rod / p.dead_volume_cap + a2 * (p.stroke_max - a.xr), 1e-9);
    d.p1 = beta1 / v1 * (q.q1 - a1 * a.vr - q_leak + x.q1);
    d.p2 = beta2 / v2 * (a2 * a.vr + q_leak - q.q2 + x.q2);
    if (a.p1 <= p.cavitation_pressure && d.p1 < 0.0) d.p1 = 0.0;
    if (a.p2 <= p.cavitation_pressure && d.p2 < 0.0) d.p2 = 0.0;
    const double f0 = (th[kMb] + th[kMw]) * p.gravity;
    const double f_tyre = tyre_contact(f0 + th[kKt] * (a.xr - xw) + th[kBt] * (a.vr - vw), th[kUni]);
    // The seal's friction is not here: simulate_actuator applies it after
    // each sub-step, implicitly (it may be a sharp step).
    d.xr = a.vr;
    d.vr = (a.p1 * a1 - a.p2 * a2 - th[kBvr] * a.vr - f_tyre - p.mass_rod * p.gravity + x.rod) / p.mass_rod;
  }

  // One RK4 sub-step of the actuator over h, then the seal's friction.
  void rk4_substep(const std::vector<double>& th, Act& a, double u, double xw, double vw, double h, const Extra& x,
                   bool seal_in) const {
    auto axpy = [](const Act& s, double k, const Act& d) {
      return Act{s.xs + k * d.xs, s.p1 + k * d.p1, s.p2 + k * d.p2, s.xr + k * d.xr, s.vr + k * d.vr};
    };
    Act k1, k2, k3, k4;
    actuator_derivatives(th, a, u, xw, vw, k1, x);
    actuator_derivatives(th, axpy(a, 0.5 * h, k1), u, xw, vw, k2, x);
    actuator_derivatives(th, axpy(a, 0.5 * h, k2), u, xw, vw, k3, x);
    actuator_derivatives(th, axpy(a, h, k3), u, xw, vw, k4, x);
    a.xs += h / 6.0 * (k1.xs + 2 * k2.xs + 2 * k3.xs + k4.xs);
    a.p1 += h / 6.0 * (k1.p1 + 2 * k2.p1 + 2 * k3.p1 + k4.p1);
    a.p2 += h / 6.0 * (k1.p2 + 2 * k2.p2 + 2 * k3.p2 + k4.p2);
    a.xr += h / 6.0 * (k1.xr + 2 * k2.xr + 2 * k3.xr + k4.xr);
    a.vr += h / 6.0 * (k1.vr + 2 * k2.vr + 2 * k3.vr + k4.vr);
    a.p1 = std::max(a.p1, p_.cavitation_pressure);
    a.p2 = std::max(a.p2, p_.cavitation_pressure);
    // The seal's Coulomb friction, split from the RK4 step and applied
    // implicitly (Moreau), so the rod can stick: a seal's step is sharp
    // (1-10 mm/s) against the 5 kg rod, a slope RK4 at 0.5 ms cannot
    // take smoothly. The earlier tanh(v_r / 0.02 m/s) was what RK4
    // could: it gained 0.98 pp against the 1 pp floor on the sweep's
    // strong Stribeck-form seal (1.16 pp now) and 1.58 on the Simscape
    // form (1.92 now).
    if (seal_in) {
      const double level = std::max(0.0, th[kSealFm] + th[kSealPc] * (std::max(0.0, a.p1 + a.p2) - seal_sum_));
      a.vr = implicit_velocity(p_.mass_rod, a.vr, 0.0, h, level, level, 0.0, 0.0);
    }
  }

  void simulate_actuator(const std::vector<double>& th, std::vector<std::vector<double>>& y, std::size_t samples,
                         const Injection* in = nullptr) const {
    const std::size_t n = t_.size();
    const bool pressures = act_outputs_ > 2;
    PiController pi(pi_);
    pi.reset();
    // x_r reaches the controller and the record through its sensor; the
    // measured x_w drives the tyre advanced by its sensor's group delay.
    SensorFilter sense_xr(sensor_form_at(th[kSensorForm]), th[kTauXr], dt_);
    sense_xr.reset(xr_[0]);
    const std::vector<double> xw_in = advanced(xw_, th[kTauXw]);
    const QuarterCarState rest = QuarterCarPlant::rest_state(p_);
    Act a{rest.x_s, rest.p1, rest.p2, xr_[0], 0.0};
    if (pressures) {  // start from the recorded pressures: the rig's state, not the nominal rest
      a.p1 = outputs_[4].measured[0];
      a.p2 = outputs_[5].measured[0];
    }
    // 5 RK4 sub-steps (0.5 ms): h w ~ 1.5 for the hydraulic mode (~480 Hz,
    // estimated from beta A^2 / V and the rod mass), inside RK4's stability
    // limit (2.8). Measured on a clean `rigctl make-run` record, baseline
    // parameters: held-out fit of p1 98.4545 % (5), 98.4507 % (10),
    // 98.4493 % (20 sub-steps), the other outputs equal to 4 digits; 10 would
    // cost twice as much for 0.004 pp.
    const int sub = 5;
    const double h = dt_ / sub;
    const bool seal_in = th[kSealFm] != 0.0 || th[kSealPc] != 0.0;
    Sample s;
    Command c;
    ControllerTerms terms;
    for (std::size_t i = 0; i < samples; ++i) {
      // The controller's feedback, through its sensor (and the where's error on it).
      const double xr_m = sense_xr.step(a.xr) + (in ? in->at(kSensorXr, i) : 0.0);
      s.value[0] = xr_m;
      pi.update(xref_[i], s, c, terms);
      const double u = std::clamp(c.value[0], -1.0, 1.0);
      y[2][i] = u;
      y[3][i] = xr_m;
      if (pressures) {
        y[4][i] = a.p1;
        y[5][i] = a.p2;
      }
      // The tyre load is driven by the wheel's true position: the measured
      // x_w less the candidate's transducer offset b_w (1840 N per 2 mm of
      // offset at kt, which the pressures show).
      const double xw0 = xw_in[i] - th[kBw] - (in ? in->at(kSensorXw, i) : 0.0);
      const double xw1 = (i + 1 < n ? xw_in[i + 1] : xw_in[i]) - th[kBw] -
                         (in ? in->at(kSensorXw, std::min(i + 1, n - 1)) : 0.0);
      const Extra x = in ? Extra{in->at(kOnRod, i), in->at(kOnSpool, i), in->at(kCrossPort, i),
                                 in->at(kIntoChamber1, i), in->at(kIntoChamber2, i)}
                         : Extra{};
      const double vw = (xw1 - xw0) / dt_;
      for (int k = 0; k < sub; ++k) {
        const double xw = xw0 + (xw1 - xw0) * (k + 0.5) / sub;
        rk4_substep(th, a, u, xw, vw, h, x, seal_in);
      }
      if (!std::isfinite(a.xr) || !std::isfinite(a.p1) || !std::isfinite(a.p2)) {
        for (std::size_t j = i; j < n; ++j)
          for (std::size_t o = 2; o < 2 + act_outputs_; ++o) y[o][j] = 1e9;
        return;
      }
    }
  }

  std::vector<double> t_, xref_, xr_, vr_, xw_, vb_, vw_, ft_, vr_load_;
  double dt_;
  QuarterCarParams p_;
  PiConfig pi_;
  std::string controller_source_;
  std::vector<Output> outputs_;
  std::size_t act_outputs_ = 2;  // u, x_r and, where recorded, p1 and p2
  double seal_sum_ = 0.0;          // [Pa] the pressure sum the seal's level F_m is at
  ReplayCache susp_cache_, act_cache_;
};

}  // namespace

std::unique_ptr<RigModel> make_quarter_car_model(const RunFile& run, const RigModelOptions& o) {
  if (!run.has("x_ref")) throw RunFileError("quarter_car: the actuator replay needs the demand column 'x_ref'");
  return std::make_unique<QuarterCarModel>(run, o);
}

}  // namespace rigctl::diag
