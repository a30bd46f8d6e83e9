// Hidden-effect tests of the half-car diagnosis (issue 6): `rigctl make-run`
// hides a cause in the simulated rig (plant physics, not the fit's formulas:
// tools/hidden_effects/half_car.cpp), and the diagnosis (tools/diagnosis/models/half_car.cpp) must
// name it, size it and show a validated gain; a clean run must give `none`;
// two causes at once must both be found.
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
};

// Strong: every cause id. Weak (level 0.35): every cause id too; the weak
// lag (7 ms, ~1.5 pp) and the weak lift-off (3.1 cm humps, ~3 pp) are the
// closest to the 1 pp acceptance threshold.
const std::vector<Case> kCases = {
    {"clean", {}},
    {"lag_strong", {"actuator_lag:strong"}},
    {"liftoff_strong", {"tyre_liftoff:strong"}},
    {"asym_strong", {"damper_asymmetry:strong"}},
    {"delay_strong", {"sensor_delay:strong"}},
    {"lag_weak", {"actuator_lag:weak"}},
    {"asym_weak", {"damper_asymmetry:weak"}},
    {"delay_weak", {"sensor_delay:weak"}},
    {"liftoff_weak", {"tyre_liftoff:weak"}},
    {"lag_and_asym", {"actuator_lag:strong", "damper_asymmetry:strong"}},
};

struct Outcome {
  bool made = false;
  std::string make_output;
  std::map<std::string, double> truth;  // "cause.param" -> value, from the truth JSON
  diag::Diagnosis d;
};

// The truth file is written by our own generator (tools/hidden_effects/make_run.cpp):
// flat enough to read its "truth": {"name": value, ...} objects by hand.
std::map<std::string, double> read_truth(const std::string& path) {
  std::ifstream f(path);
  const std::string s((std::istreambuf_iterator<char>(f)), {});
  std::map<std::string, double> out;
  std::size_t pos = 0;
  while ((pos = s.find("\"cause\": \"", pos)) != std::string::npos) {
    pos += 10;
    const std::string cause = s.substr(pos, s.find('"', pos) - pos);
    const std::size_t tb = s.find("\"truth\": {", pos), te = s.find('}', tb);
    std::string body = s.substr(tb + 10, te - tb - 10);
    std::size_t q = 0;
    while ((q = body.find('"', q)) != std::string::npos) {
      const std::size_t q2 = body.find('"', q + 1);
      const std::string key = body.substr(q + 1, q2 - q - 1);
      const std::size_t colon = body.find(':', q2);
      out[cause + "." + key] = std::stod(body.substr(colon + 1));
      q = body.find_first_of(",}", colon);
      if (q == std::string::npos) break;
    }
    pos = te;
  }
  return out;
}

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
    const std::string csv = (dir_ / (c.name + ".csv")).string(), truth = (dir_ / (c.name + ".json")).string();
    std::string cmd = std::string(RIGCTL_BINARY) + " make-run --rig half_car --config " + kConfig + " --out " + csv +
                      " --truth " + truth;
    for (const auto& e : c.effects) cmd += " --effect " + e;
    const auto r = test::run_command(cmd);
    std::lock_guard<std::mutex> lock(mutex_);
    Outcome& o = outcomes_[c.name];
    o.made = r.exit_code == 0;
    o.make_output = r.output;
    if (o.made) o.truth = read_truth(truth);
  }

  static void diagnose(const Case& c) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!outcomes_[c.name].made) return;
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
    EXPECT_TRUE(o.made) << o.make_output;
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
                               double rel) {
    const Outcome& o = outcome(run);
    const auto& d = o.d;
    EXPECT_EQ(d.cause, cause) << summary(d);
    const auto* c = find(d, cause);
    ASSERT_NE(c, nullptr) << summary(d);
    EXPECT_GE(c->gain_percent_points, 1.0) << summary(d);
    const double truth = o.truth.at(cause + "." + pname);
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
//  lag: a first-order fit of a second-order actuator: its mean delay
//       tau1 + tau2 is the low-frequency equivalent, the second pole's extra
//       phase near the wheel hop pulls the fit a little low (measured -8 %): 20 %
//  asymmetry: tanh(v / 0.01 m/s) blend vs a sharp switch, at suspension rates
//       of 0.1-0.5 m/s nearly the same law; noise only (measured +1..3 %): 10 %
//  delay: linear vs cubic interpolation between 2.5 ms samples (measured
//       within 1 %): 10 %
//  lift-off: the truth is the plant's tyre, which cannot pull (1); the
//       smooth blend may stop short where its softplus band and the plant's
//       sharp landing differ: 20 %
TEST_F(DiagnoseHalfCar, StrongActuatorLagIsNamedAndSized) { expect_found_top("lag_strong", "actuator_lag", "tau_a", 0.2); }

TEST_F(DiagnoseHalfCar, StrongDamperAsymmetryIsNamedAndSized) {
  expect_found_top("asym_strong", "damper_asymmetry", "asym", 0.1);
}

TEST_F(DiagnoseHalfCar, StrongSensorDelayIsNamedAndSized) { expect_found_top("delay_strong", "sensor_delay", "tau", 0.1); }

TEST_F(DiagnoseHalfCar, StrongTyreLiftOffIsNamed) {
  expect_found_top("liftoff_strong", "tyre_liftoff", "unilateral", 0.2);
}

TEST_F(DiagnoseHalfCar, WeakActuatorLagIsNamedAndSized) { expect_found_top("lag_weak", "actuator_lag", "tau_a", 0.2); }

TEST_F(DiagnoseHalfCar, WeakDamperAsymmetryIsNamedAndSized) {
  expect_found_top("asym_weak", "damper_asymmetry", "asym", 0.1);
}

TEST_F(DiagnoseHalfCar, WeakSensorDelayIsNamedAndSized) { expect_found_top("delay_weak", "sensor_delay", "tau", 0.1); }

TEST_F(DiagnoseHalfCar, WeakTyreLiftOffIsNamed) {
  expect_found_top("liftoff_weak", "tyre_liftoff", "unilateral", 0.2);
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
  EXPECT_NEAR(tau, o.truth.at("actuator_lag.tau_a"), 0.2 * o.truth.at("actuator_lag.tau_a")) << summary(d);
  EXPECT_NEAR(a, o.truth.at("damper_asymmetry.asym"), 0.1 * o.truth.at("damper_asymmetry.asym")) << summary(d);
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
