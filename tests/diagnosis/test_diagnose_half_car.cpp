// Hidden-effect tests of the half-car diagnosis (issues 6, 14): `rigctl make-run`
// hides a cause in the simulated rig (plant physics, not the fit's formulas:
// tools/hidden_effects/half_car.cpp), and the diagnosis (tools/diagnosis/models/half_car.cpp) must
// name it, size it and show a validated gain; a clean run must give `none`;
// two causes at once must both be found. Every run is a perturbed world
// (plant parameters within +-5 %, controller and road varied:
// docs/diagnosis.md 7); the truth is what make-run wrote to its truth file.
//
// CPU: every run is generated first (separate processes), then the diagnoses
// run two at a time in threads (CI has two cores).
#include <gtest/gtest.h>

#include <algorithm>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "allocation_counter.hpp"
#include "plant/half_car/half_car_plant.hpp"
#include "plant/half_car/road_profile.hpp"
#include "hidden_run.hpp"
#include "process.hpp"
#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

namespace fs = std::filesystem;

const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/half_car.yaml";

struct Case {
  std::string name;
  std::vector<std::string> effects;  // CAUSE:LEVEL for make-run
  int form = -1;                     // -1: make-run's default (seed 1: form 1)
};

// A representative set at the strong level (every cause at both levels and
// both forms is the sweep's job: `rigctl bench --section diagnosis_sweep
// --sweep-rig half_car`, BENCHMARKS.md). The damper asymmetry is sized in
// its piecewise-linear form (0) in the two-effect run; alone it is made
// digressive (form 1) and checked by name and sign only (see its test).
// Measured on the piecewise form alone (seed 1): named with asym 0.39
// against 0.33 and a false second cause (actuator_lag at 2.1 pp): an open
// finding of the diagnosis (BENCHMARKS.md), not covered by a wider tolerance.
const std::vector<Case> kCases = {
    {"clean", {}},
    {"lag_strong", {"actuator_lag:strong"}},  // first-order actuator (form 1)
    {"liftoff_strong", {"tyre_liftoff:strong"}},
    {"asym_strong", {"damper_asymmetry:strong"}},  // digressive (form 1)
    {"delay_strong", {"sensor_delay:strong"}},  // Butterworth conditioning filter (form 1)
    {"lag_and_asym", {"actuator_lag:strong", "damper_asymmetry:strong"}, 0},
};

struct Outcome {
  test::HiddenRun run;
  diag::Diagnosis d;
};

class DiagnoseHalfCar : public ::testing::Test {
 protected:
  // Runs are made and diagnosed on first use, one case at a time: ctest
  // runs every TEST in a process of its own (gtest_discover_tests), so a
  // suite-wide set-up would redo every case once per test.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("rigctl_diag_half_car_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  static void make(const Case& c) {
    auto run = test::make_hidden_run(RIGCTL_BINARY, "half_car", kConfig, c.effects, 1, c.form,
                                     (dir_ / (c.name + ".csv")).string());
    std::lock_guard<std::mutex> lock(mutex_);
    outcomes_[c.name].run = std::move(run);
  }

  static void diagnose(const Case& c) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!outcomes_[c.name].run.made) return;
    }
    const auto rf = read_run_file((dir_ / (c.name + ".csv")).string(), run_file_columns(RunFileRig::kHalfCar));
    diag::RigModelOptions mo;
    mo.config_path = kConfig;
    const auto model = diag::make_rig_model(RunFileRig::kHalfCar, rf, mo);
    diag::Diagnosis d = diag::diagnose(*model, {});
    std::lock_guard<std::mutex> lock(mutex_);
    outcomes_[c.name].d = std::move(d);
  }

  static const Outcome& outcome(const std::string& name) {
    bool known;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      known = outcomes_.count(name) > 0;
    }
    if (!known) {
      const auto c = std::find_if(kCases.begin(), kCases.end(), [&](const Case& k) { return k.name == name; });
      if (c == kCases.end()) throw std::invalid_argument("no case " + name);
      make(*c);
      diagnose(*c);
    }
    const Outcome& o = outcomes_.at(name);
    EXPECT_TRUE(o.run.made) << o.run.output;
    return o;
  }

  static std::string summary(const diag::Diagnosis& d) {
    std::ostringstream s;
    s << "cause " << d.cause << ";";
    for (const auto& c : d.causes) {
      s << " " << c.cause << " gain " << c.gain_percent_points << " pp on " << c.signal;
      for (const auto& p : c.parameters) s << " " << p.name << "=" << p.value;
      s << ";";
    }
    for (const auto& sc : d.screened)
      if (sc.refitted) s << " [r" << sc.round << " " << sc.cause << " " << sc.gain_percent_points << ": " << sc.reason << "]";
    return s.str();
  }

  static const diag::CauseResult* find(const diag::Diagnosis& d, const std::string& cause) {
    for (const auto& c : d.causes)
      if (c.cause == cause) return &c;
    return nullptr;
  }

  static double param(const diag::CauseResult& c, const std::string& name) {
    for (const auto& p : c.parameters)
      if (p.name == name) return p.value;
    ADD_FAILURE() << c.cause << " has no parameter " << name;
    return NAN;
  }

  // Named as the top cause, with a validated gain, strength within rel of the truth.
  static void expect_found_top(const std::string& run, const std::string& cause, const std::string& pname,
                               double rel, const std::string& truth_name = "") {
    const Outcome& o = outcome(run);
    const auto& d = o.d;
    EXPECT_EQ(d.cause, cause) << summary(d);
    const auto* c = find(d, cause);
    ASSERT_NE(c, nullptr) << summary(d);
    EXPECT_GE(c->gain_percent_points, 1.0) << summary(d);
    const double truth = o.run.truth.at(cause + "." + (truth_name.empty() ? pname : truth_name));
    EXPECT_NEAR(param(*c, pname), truth, rel * std::abs(truth)) << summary(d);
  }

  static fs::path dir_;
  static std::map<std::string, Outcome> outcomes_;
  static std::mutex mutex_;
};

fs::path DiagnoseHalfCar::dir_;
std::map<std::string, Outcome> DiagnoseHalfCar::outcomes_;
std::mutex DiagnoseHalfCar::mutex_;

TEST_F(DiagnoseHalfCar, CleanRunGivesNone) {
  const auto& d = outcome("clean").d;
  EXPECT_EQ(d.cause, "none") << summary(d);
  EXPECT_TRUE(d.causes.empty()) << summary(d);
  // The replay itself is right: the baseline fits the clean record closely.
  EXPECT_GT(d.baseline_fit_percent.at("z_s"), 90.0) << summary(d);
  EXPECT_GT(d.baseline_fit_percent.at("z_u1"), 90.0) << summary(d);
}

// Tolerances: the plant's effect is not the fit's formula, so the fitted
// strength is the best equivalent, not the plant's number. Why each:
//  lag: in its first form (the two-effect run) a first-order fit of a
//       second-order actuator: its mean delay tau1 + tau2 is the
//       low-frequency equivalent, the second pole's extra phase near the
//       wheel hop pulls the fit a little low (measured -8 %): 20 %; the
//       single-effect run's first-order actuator is the fit's own law
//  asymmetry: tanh(v / 0.01 m/s) blend vs a sharp switch, at suspension rates
//       of 0.1-0.5 m/s nearly the same law; noise only (measured +1..3 %): 10 %
//  delay: the conditioning filter's low-frequency group delay (the truth)
//       against the fit's linearly interpolated pure delay: 10 %
//  lift-off: the truth is the plant's tyre, which cannot pull (1); the
//       smooth blend may stop short where its softplus band and the plant's
//       sharp landing differ: 20 %
TEST_F(DiagnoseHalfCar, StrongActuatorLagIsNamedAndSized) { expect_found_top("lag_strong", "actuator_lag", "tau_a", 0.2); }

// The digressive damper's rebound slope drops to a third above 0.1 m/s, so
// over the run's suspension rates (0.1-0.5 m/s) its equivalent asymmetry is
// below the truth's low-speed ratio (measured 0.14 against 0.43) yet, at the
// strong level, still rebound-heavy: the fit must lie between symmetric and
// the low-speed ratio. No single number is the truth to size it against.
TEST_F(DiagnoseHalfCar, StrongDigressiveDamperAsymmetryIsNamed) {
  const Outcome& o = outcome("asym_strong");
  EXPECT_EQ(o.run.forms.at("damper_asymmetry"), "digressive");
  EXPECT_EQ(o.d.cause, "damper_asymmetry") << summary(o.d);
  const auto* c = find(o.d, "damper_asymmetry");
  ASSERT_NE(c, nullptr) << summary(o.d);
  EXPECT_GE(c->gain_percent_points, 1.0) << summary(o.d);
  EXPECT_GT(param(*c, "asym"), 0.0) << summary(o.d);
  EXPECT_LT(param(*c, "asym"), o.run.truth.at("damper_asymmetry.asym")) << summary(o.d);
}

// The generator delays all four transducers alike: the body's is compared.
TEST_F(DiagnoseHalfCar, StrongSensorDelayIsNamedAndSized) {
  expect_found_top("delay_strong", "sensor_delay", "tau_z_s", 0.1, "tau");
}

TEST_F(DiagnoseHalfCar, StrongTyreLiftOffIsNamed) {
  expect_found_top("liftoff_strong", "tyre_liftoff", "unilateral", 0.2);
}

TEST_F(DiagnoseHalfCar, ActuatorLagAndDamperAsymmetryTogetherAreBothFound) {
  const Outcome& o = outcome("lag_and_asym");
  const auto& d = o.d;
  const auto* lag = find(d, "actuator_lag");
  const auto* asym = find(d, "damper_asymmetry");
  ASSERT_NE(lag, nullptr) << summary(d);
  ASSERT_NE(asym, nullptr) << summary(d);
  EXPECT_GE(lag->gain_percent_points, 1.0) << summary(d);
  EXPECT_GE(asym->gain_percent_points, 1.0) << summary(d);
  EXPECT_EQ(d.causes.size(), 2u) << summary(d);
  // Sized from the final joint fit (both effects in).
  double tau = NAN, a = NAN;
  for (const auto& p : d.final_parameters) {
    if (p.name == "tau_a") tau = p.value;
    if (p.name == "asym") a = p.value;
  }
  EXPECT_NEAR(tau, o.run.truth.at("actuator_lag.tau_a"), 0.2 * o.run.truth.at("actuator_lag.tau_a")) << summary(d);
  EXPECT_NEAR(a, o.run.truth.at("damper_asymmetry.asym"), 0.1 * o.run.truth.at("damper_asymmetry.asym")) << summary(d);
}

// ------------------------------------------- the generator's plant physics

// The hidden actuator lag: command -> valve stage (tau2) -> force loop (tau1),
// integrated inside the plant; the step response is the two-pole one,
// 1 - (tau1 e^(-t/tau1) - tau2 e^(-t/tau2)) / (tau1 - tau2), and advance()
// stays allocation-free with it.
TEST(HalfCarPlantEffects, SecondOrderActuatorFollowsTwoLagsWithoutAllocating) {
  HalfCarParams p;
  p.road.kind = RoadKind::kFlat;
  p.actuator_time_constant = 0.012;
  p.actuator_valve_time_constant = 0.008;
  HalfCarPlant plant(p);
  const std::array<double, 2> cmd{1000.0, -500.0};
  std::array<double, half_car_signal::kCount> out{};
  const long before = test::allocation_count();
  for (int k = 0; k < 8; ++k) plant.advance(cmd, 0.0025);  // 20 ms
  plant.measure(out);
  EXPECT_EQ(test::allocation_count(), before);
  const double t = 0.02, t1 = 0.012, t2 = 0.008;
  const double step = 1.0 - (t1 * std::exp(-t / t1) - t2 * std::exp(-t / t2)) / (t1 - t2);
  EXPECT_NEAR(out[half_car_signal::kSimFAct1], 1000.0 * step, 0.01);
  EXPECT_NEAR(out[half_car_signal::kSimFAct2], -500.0 * step, 0.01);
  // Slower than the first-order lag of the same mean delay at first (S-shaped start).
  EXPECT_LT(out[half_car_signal::kSimFAct1], 1000.0 * (1.0 - std::exp(-t / (t1 + t2))));
  p.actuator_time_constant = 0.0;  // a valve stage alone is refused: it feeds the force loop
  EXPECT_THROW(HalfCarPlant{p}, std::invalid_argument);
}

// The road of the diagnosis case: humps of the bump train at start + k interval
// under wheel 1, the wheelbase / V later under wheel 2, on top of the kind.
TEST(HalfCarPlantEffects, BumpTrainLaysEqualHumpsOnTheRoad) {
  RoadProfileSpec spec;
  spec.kind = RoadKind::kFlat;
  spec.train = {0.03, 1.5, 1.0, 0.85, 3};
  const RoadProfile road(spec, 20.0, WheelArrangement::kInLine, 2.68);
  const double half = 0.5 * 1.5 / 20.0;  // crest: half the hump's duration in
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(road.height(0, 1.0 + 0.85 * k + half), 0.03, 1e-12) << k;
    EXPECT_NEAR(road.height(1, 1.0 + 0.85 * k + half + 2.68 / 20.0), 0.03, 1e-12) << k;
    EXPECT_EQ(road.height(0, 1.0 + 0.85 * k + 0.5), 0.0) << k;  // between humps
  }
  EXPECT_EQ(road.height(0, 1.0 + 0.85 * 3 + half), 0.0);  // count humps only
  EXPECT_EQ(road.height(0, 0.99), 0.0);
  spec.train.interval = 0.05;  // shorter than a hump (75 ms): overlapping humps are refused
  EXPECT_THROW(RoadProfile(spec, 20.0, WheelArrangement::kInLine, 2.68), std::invalid_argument);
}

}  // namespace
}  // namespace rigctl
