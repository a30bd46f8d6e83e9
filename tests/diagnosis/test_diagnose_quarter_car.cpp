// Hidden-effect tests of the quarter car's diagnosis: `make_run` hides one
// effect (or two, or none) in the simulated closed loop with sensor noise and
// quantisation, the diagnosis must name it, fit its size within a stated
// tolerance of the truth, and show a positive held-out gain. The generator's
// physics is not the candidate's formula (plant/quarter_car/quarter_car_params.hpp,
// QuarterCarHiddenEffects), so the tolerances compare physically equivalent
// quantities.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <algorithm>
#include <map>
#include <mutex>
#include <sstream>

#include "plant/quarter_car/bearing_friction.hpp"
#include "plant/quarter_car/quarter_car_params.hpp"
#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

struct Case {
  std::string name;
  std::vector<std::pair<std::string, double>> effects;
  int seed = 1;
};

struct Outcome {
  std::vector<AppliedEffect> applied;
  diag::Diagnosis diagnosis;
  std::string error;
};

const std::vector<Case>& cases() {
  static const std::vector<Case> c{
      {"clean", {}, 3},
      {"bearing_friction_strong", {{"bearing_friction", 1.0}}},
      {"bearing_friction_weak", {{"bearing_friction", weak_level()}}},
      {"actuator_seal_friction_strong", {{"actuator_seal_friction", 1.0}}},
      {"cross_port_leakage_strong", {{"cross_port_leakage", 1.0}}},
      {"valve_deadband_strong", {{"valve_deadband", 1.0}}},
      {"valve_deadband_weak", {{"valve_deadband", weak_level()}}},
      {"entrained_air_strong", {{"entrained_air", 1.0}}},
      {"sensor_delay_strong", {{"sensor_delay", 1.0}}},
      {"sensor_offset_strong", {{"sensor_offset", 1.0}}},
      {"sensor_offset_weak", {{"sensor_offset", weak_level()}}},
      {"tyre_liftoff_strong", {{"tyre_liftoff", 1.0}}},
      {"damper_asymmetry_strong", {{"damper_asymmetry", 1.0}}},
      {"two_at_once", {{"bearing_friction", 1.0}, {"cross_port_leakage", 1.0}}, 2},
  };
  return c;
}

Outcome run_case(const Case& c, const std::string& dir) {
  Outcome o;
  try {
    MakeRunOptions m;
    m.rig = RigKind::kQuarterCar;
    m.config_path = RIGCTL_SOURCE_DIR "/config/quarter_car.yaml";
    m.effects = c.effects;
    m.seed = c.seed;
    m.out_csv = dir + "/" + c.name + ".csv";
    std::ostringstream quiet;
    o.applied = make_run(m, quiet);
    const auto rf = read_run_file(m.out_csv, run_file_columns(RunFileRig::kQuarterCar));
    const auto model = diag::make_rig_model(RunFileRig::kQuarterCar, rf, {});
    o.diagnosis = diag::diagnose(*model, {});
  } catch (const std::exception& e) {
    o.error = e.what();
  }
  return o;
}

// Each case is made and diagnosed on first use: ctest runs every TEST in a
// process of its own (gtest_discover_tests), and ctest -j spreads them over
// the cores, so a TEST computes only the cases it checks.
const Outcome& outcome(const std::string& name) {
  static std::map<std::string, Outcome> done;
  static std::mutex m;
  std::lock_guard<std::mutex> lock(m);
  auto it = done.find(name);
  if (it == done.end()) {
    const auto c = std::find_if(cases().begin(), cases().end(), [&](const Case& k) { return k.name == name; });
    if (c == cases().end()) throw std::invalid_argument("no case " + name);
    const std::string dir = std::filesystem::temp_directory_path() / ("rigctl_qc_hidden_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    it = done.emplace(name, run_case(*c, dir)).first;
    std::filesystem::remove_all(dir);
  }
  EXPECT_TRUE(it->second.error.empty()) << name << ": " << it->second.error;
  return it->second;
}

const diag::CauseResult* found(const Outcome& o, const std::string& cause) {
  for (const auto& c : o.diagnosis.causes)
    if (c.cause == cause) return &c;
  return nullptr;
}

double fitted(const diag::CauseResult& c, const std::string& name) {
  for (const auto& p : c.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name << " in " << c.cause;
  return NAN;
}

double truth(const Outcome& o, const std::string& cause, const std::string& name) {
  for (const auto& a : o.applied)
    if (a.cause == cause) return a.truth.at(name);
  ADD_FAILURE() << "no truth " << name;
  return NAN;
}

std::string summary(const Outcome& o) {
  std::ostringstream s;
  s << "cause " << o.diagnosis.cause << "; screened:";
  for (const auto& c : o.diagnosis.screened)
    if (c.refitted) s << " " << c.cause << " " << c.gain_percent_points << " pp (" << c.reason << ");";
  return s.str();
}

// The named cause is the top one, with a positive validated gain; returns it.
const diag::CauseResult* expect_named(const std::string& case_name, const std::string& cause) {
  const Outcome& o = outcome(case_name);
  EXPECT_EQ(o.diagnosis.cause, cause) << summary(o);
  const auto* c = found(o, cause);
  if (c) {
    EXPECT_GT(c->gain_percent_points, 0.0) << summary(o);
  }
  return c;
}

TEST(HiddenEffectsQuarterCar, CleanRunGivesNone) {
  const Outcome& o = outcome("clean");
  EXPECT_EQ(o.diagnosis.cause, "none") << summary(o);
  EXPECT_TRUE(o.diagnosis.causes.empty()) << summary(o);
}

TEST(HiddenEffectsQuarterCar, BearingFriction) {
  // The sliding friction at 5 cm/s (a typical body speed of the diagnosis
  // run) and the static normal force: the Karnopp truth's Stribeck law
  // against the fitted one. Breakaway itself is poorly excited by a run that
  // keeps the body moving (the fit may put the stiction excess to 0).
  QuarterCarParams nominal;
  const auto& bf = nominal.bearing_friction;
  const double weight = nominal.mass_body * nominal.gravity;
  const double fn = bearing_friction_levels(bf, weight, 0.0, 0.0).normal;
  const double v = 0.05;
  const double stribeck = std::exp(-std::pow(v / bf.stribeck_velocity, bf.stribeck_exponent));
  for (const char* name : {"bearing_friction_strong", "bearing_friction_weak"}) {
    const auto* c = expect_named(name, "bearing_friction");
    if (!c) continue;
    const Outcome& o = outcome(name);
    const double level = o.applied.front().level;
    const double want = truth(o, "bearing_friction", "Fc") + bf.normal_coefficient * level * fn +
                        truth(o, "bearing_friction", "dFs") * stribeck + truth(o, "bearing_friction", "D") * v;
    const double got = fitted(*c, "Fc") + fitted(*c, "mu") * fn + fitted(*c, "dFs") * std::exp(-std::pow(v / 0.015, 2)) +
                       fitted(*c, "D") * v;
    EXPECT_NEAR(got, want, 0.4 * want) << name << " (static normal force " << fn << " N)";
  }
}

TEST(HiddenEffectsQuarterCar, ActuatorSealFriction) {
  const auto* c = expect_named("actuator_seal_friction_strong", "actuator_seal_friction");
  if (!c) return;
  const Outcome& o = outcome("actuator_seal_friction_strong");
  // Coulomb level at the ~200 bar pressure sum of this rig.
  const double sum = 200e5;
  const double want = truth(o, "actuator_seal_friction", "F_pr") + truth(o, "actuator_seal_friction", "f_c") * sum;
  EXPECT_NEAR(fitted(*c, "F_pr") + fitted(*c, "f_c") * sum, want, 0.5 * want);
}

TEST(HiddenEffectsQuarterCar, CrossPortLeakage) {
  const auto* c = expect_named("cross_port_leakage_strong", "cross_port_leakage");
  if (!c) return;
  const Outcome& o = outcome("cross_port_leakage_strong");
  // The laminar conductance that leaks as much as the worn seal's orifice at 50 bar.
  const double want = truth(o, "cross_port_leakage", "extra_leak_at_50bar_m3_s") / 50e5;
  EXPECT_NEAR(fitted(*c, "C_il"), want, 0.5 * want);
}

TEST(HiddenEffectsQuarterCar, ValveDeadband) {
  for (const char* name : {"valve_deadband_strong", "valve_deadband_weak"}) {
    const auto* c = expect_named(name, "valve_deadband");
    if (!c) continue;
    const double want = truth(outcome(name), "valve_deadband", "overlap");
    EXPECT_NEAR(fitted(*c, "delta"), want, 0.3 * want) << name;
  }
}

TEST(HiddenEffectsQuarterCar, EntrainedAir) {
  const auto* c = expect_named("entrained_air_strong", "entrained_air");
  if (!c) return;
  const double want = truth(outcome("entrained_air_strong"), "entrained_air", "beta_ratio_at_75bar");
  EXPECT_NEAR(fitted(*c, "beta_ratio"), want, 0.15);
}

TEST(HiddenEffectsQuarterCar, SensorDelay) {
  const auto* c = expect_named("sensor_delay_strong", "sensor_delay");
  if (!c) return;
  const double want = truth(outcome("sensor_delay_strong"), "sensor_delay", "tau");
  EXPECT_NEAR(fitted(*c, "tau"), want, 0.2 * want);
}

TEST(HiddenEffectsQuarterCar, SensorOffset) {
  for (const char* name : {"sensor_offset_strong", "sensor_offset_weak"}) {
    const auto* c = expect_named(name, "sensor_offset");
    if (!c) continue;
    const double want = truth(outcome(name), "sensor_offset", "b_b");
    EXPECT_NEAR(fitted(*c, "b_b"), want, 0.1 * want) << name;
    EXPECT_NEAR(fitted(*c, "b_w"), 0.0, 0.1 * want) << name;
  }
}

TEST(HiddenEffectsQuarterCar, TyreLiftoff) {
  const auto* c = expect_named("tyre_liftoff_strong", "tyre_liftoff");
  if (!c) return;
  EXPECT_NEAR(fitted(*c, "unilateral"), truth(outcome("tyre_liftoff_strong"), "tyre_liftoff", "pull_loss"), 0.3);
}

TEST(HiddenEffectsQuarterCar, DamperAsymmetry) {
  const auto* c = expect_named("damper_asymmetry_strong", "damper_asymmetry");
  if (!c) return;
  const double want = truth(outcome("damper_asymmetry_strong"), "damper_asymmetry", "dc");
  EXPECT_NEAR(fitted(*c, "dc"), want, 0.3 * std::abs(want));
}

TEST(HiddenEffectsQuarterCar, TwoEffectsAtOnceAreBothFound) {
  const Outcome& o = outcome("two_at_once");
  EXPECT_NE(found(o, "bearing_friction"), nullptr) << summary(o);
  EXPECT_NE(found(o, "cross_port_leakage"), nullptr) << summary(o);
  for (const auto& c : o.diagnosis.causes) EXPECT_GT(c.gain_percent_points, 0.0) << c.cause;
}

}  // namespace
}  // namespace rigctl
