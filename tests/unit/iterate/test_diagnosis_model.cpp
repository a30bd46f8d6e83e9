// The model a diagnosis extended, written into the rig's config for the
// drive iteration's inverse, and the drive FRF from a model.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "config/rig_config.hpp"
#include "tools/iterate/diagnosis_model.hpp"
#include "tools/iterate/drive_frf.hpp"

namespace rigctl {
namespace {

RigConfig quarter_car() { return load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml"); }

std::string write(const std::string& name, const std::string& text) {
  const std::string p = (std::filesystem::path(::testing::TempDir()) / name).string();
  std::ofstream(p) << text;
  return p;
}

TEST(DiagnosisModel, FinalParametersGoIntoThePlantUndeterminedOnesStay) {
  const RigConfig nominal = quarter_car();
  const auto m = diagnosis_model(nominal, write("d.json", R"({"rig": "quarter_car", "cause": "cross_port_leakage",
      "final_parameters": {"ks": 30000.0, "Mw": null, "kv_scale": 0.9, "R_l": 1.0e11, "C_il": 3.0e-12,
                           "beta_ratio": 0.5, "beta": 1.2e9, "tau": 0.01}})"));
  const QuarterCarParams& p = m.config.quarter_car;
  EXPECT_DOUBLE_EQ(p.spring_stiffness, 30000.0);
  EXPECT_DOUBLE_EQ(p.mass_wheel, nominal.quarter_car.mass_wheel);  // null: undetermined
  EXPECT_DOUBLE_EQ(p.valve_flow_gain, 0.9 * nominal.quarter_car.valve_flow_gain);
  EXPECT_DOUBLE_EQ(p.leakage_resistance, 1.0e11);
  EXPECT_DOUBLE_EQ(p.hidden.extra_laminar_leak, 3.0e-12);
  EXPECT_DOUBLE_EQ(p.bulk_modulus, 0.6e9);  // beta, then the entrained air's ratio
  EXPECT_EQ(m.ignored, (std::vector<std::string>{"Mw", "tau"}));  // tau: a sensor's delay, not the plant's
}

// The candidates' own parameters, through the constants their laws are
// written around: entrained air as the mixture law's air fraction with the
// candidate's bubble index, the seal's level F_m at the pressure sum P_m
// (not the supply pressure: six generated runs had a mean p1 + p2 of 73-79 %
// of it).
TEST(DiagnosisModel, AirFractionAndSealLevelGoIntoThePlant) {
  const auto m = diagnosis_model(quarter_car(), write("a.json", R"({"rig": "quarter_car", "cause": "entrained_air",
      "final_parameters": {"alpha": 0.05, "F_m": 300.0, "f_c": 5.0e-6, "Ps": 2.0e7},
      "model_constants": {"P_m": 1.5e7, "air_bubble_index": 1.2}})"));
  const QuarterCarParams& p = m.config.quarter_car;
  EXPECT_DOUBLE_EQ(p.hidden.air_fraction, 0.05);
  EXPECT_DOUBLE_EQ(p.hidden.air_polytropic_index, 1.2);
  EXPECT_DOUBLE_EQ(p.hidden.seal_pressure_coefficient, 5.0e-6);
  EXPECT_NEAR(p.hidden.seal_preload, 300.0 - 5.0e-6 * 1.5e7, 1e-9);
  EXPECT_TRUE(m.ignored.empty());
}

// Without the constants (a diagnosis written before them) the level and the
// air fraction cannot be placed: the config's values stay, and they are
// listed as ignored rather than mapped at a guessed pressure.
TEST(DiagnosisModel, ALevelWithoutItsConstantIsIgnoredNotGuessed) {
  const RigConfig nominal = quarter_car();
  const auto m = diagnosis_model(nominal, write("b.json", R"({"rig": "quarter_car", "cause": "entrained_air",
      "final_parameters": {"alpha": 0.05, "F_m": 300.0, "f_c": 5.0e-6}})"));
  EXPECT_EQ(m.ignored, (std::vector<std::string>{"alpha", "F_m"}));
  EXPECT_DOUBLE_EQ(m.config.quarter_car.hidden.seal_preload, nominal.quarter_car.hidden.seal_preload);
  EXPECT_DOUBLE_EQ(m.config.quarter_car.hidden.air_fraction, nominal.quarter_car.hidden.air_fraction);
}

TEST(DiagnosisModel, TheShippedDiagnosisMapsOntoTheQuarterCar) {
  const auto m = diagnosis_model(quarter_car(), std::string(RIGCTL_TEST_DATA) + "/quarter_car_worn_seal_diagnosis.json");
  EXPECT_GE(m.applied.size(), 8u);
  EXPECT_LT(m.config.quarter_car.leakage_resistance, quarter_car().quarter_car.leakage_resistance);  // a leakier rig
}

TEST(DiagnosisModel, AnotherRigOrNoDiagnosisIsRefusedNamingTheFile) {
  const RigConfig c = quarter_car();
  auto fails_with = [&](const std::string& path, const std::string& text) {
    try {
      diagnosis_model(c, path);
      ADD_FAILURE() << "accepted " << path;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  };
  fails_with(write("p.json", R"({"rig": "pneumatic_rotary", "final_parameters": {"J": 1}})"), "a diagnosis of pneumatic_rotary");
  fails_with(write("n.json", R"({"format": "rigctl-frf"})"), "needs the keys rig and final_parameters");
  fails_with(write("x.json", "{not json"), "not a diagnosis JSON file");
}

TEST(DriveFrfModel, WheelFollowsTheRodAtLowFrequencyAndLagsAtTheWheelHop) {
  const RigConfig c = quarter_car();
  const auto f = model_frequencies(0.5, 40.0);
  const DriveFrf wheel = drive_frf_from_model(c, "x_w", 0.08, f, "nominal model");
  const DriveFrf rod = drive_frf_from_model(c, "x_r", 0.08, f, "nominal model");
  // The linearisation holds the body on its bearing (stuck, as under small
  // motion): the wheel then sits between the tyre and the spring, and moves
  // kt / (kt + ks) = 0.97 of the rod at low frequency.
  const auto& p = c.quarter_car;
  EXPECT_NEAR(std::abs(wheel.at(0.5)), p.tyre_stiffness / (p.tyre_stiffness + p.spring_stiffness), 0.01);
  EXPECT_NEAR(std::abs(rod.at(0.5)), 1.0, 0.02);  // the PI's integral: no steady error
  EXPECT_LT(std::abs(rod.at(30.0)), 0.5);            // beyond the ~4 Hz crossover
  EXPECT_LT(std::arg(wheel.at(10.0)), std::arg(rod.at(10.0)));  // the tyre adds lag
  EXPECT_THROW(drive_frf_from_model(c, "theta", 0.08, f, "m"), std::invalid_argument);
}

}  // namespace
}  // namespace rigctl
