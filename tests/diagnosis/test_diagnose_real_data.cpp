// Model-discrepancy diagnosis on the two real records in tests/data/ and on
// seed 000's own story (a simulated quarter-car run with body-bearing friction
// against the frictionless baseline). Each case runs the full pipeline once.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "process.hpp"
#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

diag::Diagnosis run_diagnosis(RunFileRig rig, const std::string& path) {
  const auto rf = read_run_file(path, run_file_columns(rig));
  const auto model = diag::make_rig_model(rig, rf, {});
  return diag::diagnose(*model, {});
}

double param(const diag::Diagnosis& d, const std::string& name) {
  for (const auto& p : d.final_parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return NAN;
}

void expect_near_rel(double v, double ref, double rel, const char* what) {
  EXPECT_NEAR(v, ref, std::abs(ref) * rel) << what << " = " << v << ", published " << ref;
}

TEST(DiagnoseRealData, EmpsNamesCoulombThenAsymmetricFriction) {
  const auto d = run_diagnosis(RunFileRig::kLinearAxis, RIGCTL_TEST_DATA "/emps_estimation.csv");
  ASSERT_GE(d.causes.size(), 2u);
  EXPECT_EQ(d.cause, "coulomb_friction");
  EXPECT_EQ(d.causes[0].cause, "coulomb_friction");
  EXPECT_EQ(d.causes[1].cause, "asymmetric_friction");
  EXPECT_GT(d.causes[0].gain_percent_points, 1.0);
  EXPECT_GT(d.causes[1].gain_percent_points, 1.0);
  // Janot, Gautier, Brunot 2019 (IDIM-LS): M 95.11, Fv 203.5, Fc 20.39; asymmetric
  // Fv+ 166.7, Fv- 240.4, Fc+ 20.14, Fc- 20.63. Within 15 %.
  expect_near_rel(param(d, "M"), 95.11, 0.15, "M");
  expect_near_rel(param(d, "Fv"), 203.5, 0.15, "Fv");
  expect_near_rel(param(d, "Fc"), 20.39, 0.15, "Fc");
  expect_near_rel(d.causes[0].parameters[0].value, 20.39, 0.15, "Fc (Coulomb step alone)");
  const double fv = param(d, "Fv"), dfv = param(d, "dFv"), fc = param(d, "Fc"), dfc = param(d, "dFc");
  expect_near_rel(fv + dfv, 166.7, 0.15, "Fv+");
  expect_near_rel(fv - dfv, 240.4, 0.15, "Fv-");
  expect_near_rel(fc + dfc, 20.14, 0.15, "Fc+");
  expect_near_rel(fc - dfc, 20.63, 0.15, "Fc-");
  std::ostringstream js;
  diag::write_json(d, js);
  EXPECT_NE(js.str().find("\"cause\": \"coulomb_friction\""), std::string::npos);
}

TEST(DiagnoseRealData, MrDamperNamesHysteresisAndCommandLag) {
  const auto d = run_diagnosis(RunFileRig::kDamper, RIGCTL_TEST_DATA "/mr_damper_random_50.csv");
  bool hyst = false, lag = false;
  for (const auto& c : d.causes) {
    if (c.cause == "hysteresis") hyst = c.gain_percent_points > 1.0;
    if (c.cause == "command_lag") lag = c.gain_percent_points > 1.0;
  }
  EXPECT_TRUE(hyst) << "hysteresis not named with a gain";
  EXPECT_TRUE(lag) << "command_lag not named with a gain";
}

TEST(DiagnoseSeed000, BearingFrictionAgainstFrictionlessBaseline) {
  const std::string csv = ::testing::TempDir() + "/qc_bearing.csv";
  const std::string lcm = ::testing::TempDir() + "/qc_bearing.lcm";
  const auto run = test::run_command(std::string(RIGCTL_BINARY) + " run " RIGCTL_SOURCE_DIR
                                     "/config/quarter_car.yaml --fast --no-realtime --csv " + csv + " --log " + lcm);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string json = ::testing::TempDir() + "/qc.json", html = ::testing::TempDir() + "/qc.html";
  const auto r = test::run_command(std::string(RIGCTL_BINARY) + " diagnose --rig quarter_car --data " + csv +
                                   " --json " + json + " --report " + html + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream jf(json);
  const std::string j((std::istreambuf_iterator<char>(jf)), {});
  EXPECT_NE(j.find("\"cause\": \"bearing_friction\""), std::string::npos) << j;
  EXPECT_NE(j.find("\"signal\": \"x_b\""), std::string::npos) << j;
  std::ifstream hf(html);
  const std::string h((std::istreambuf_iterator<char>(hf)), {});
  EXPECT_NE(h.find("<svg"), std::string::npos);
  EXPECT_NE(h.find("bearing_friction vs body velocity"), std::string::npos);
  EXPECT_EQ(h.find("<script"), std::string::npos);  // self-contained, no JS
}

TEST(DiagnoseCli, BadInputGivesOneLineReasonAndNonZeroExit) {
  const std::string bad = ::testing::TempDir() + "/bad_run.csv";
  {
    std::ofstream f(bad);
    f << "# rig: damper\nt,x,f\n0,0,1\n0.001,,2\n";
    for (int i = 2; i < 30; ++i) f << i * 0.001 << ",0,1\n";
  }
  auto r = test::run_command(std::string(RIGCTL_BINARY) + " diagnose --rig damper --data " + bad);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("line 4, column 'x'"), std::string::npos) << r.output;
  r = test::run_command(std::string(RIGCTL_BINARY) + " diagnose --rig linear_axis --data " + bad);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("missing required column 'u'"), std::string::npos) << r.output;
  r = test::run_command(std::string(RIGCTL_BINARY) + " diagnose --rig bicycle --data " + bad);
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace rigctl
