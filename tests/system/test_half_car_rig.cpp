// The half car end to end through its config (config/half_car.yaml): the
// `rigctl run`, `compare` and `optimize` programs, the issue's claims on the
// compare report's own numbers, the fuzzy engine read from the config, and
// clear errors for bad half_car keys.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "process.hpp"
#include "config_edit.hpp"
#include "read_file.hpp"
#include "rt/control/fuzzy_engine.hpp"
#include "rt/control/setpoint_profile.hpp"
#include "tools/run/rig_assembly.hpp"

using namespace rigctl;
using rigctl::test::run_command;
namespace fs = std::filesystem;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/half_car.yaml";

using rigctl::test::read_file;

class HalfCarRig : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_half_car_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// The header row and the number of data rows of a run file.
std::pair<std::vector<std::string>, int> csv_shape(const std::string& p) {
  std::ifstream in(p);
  std::string line;
  std::vector<std::string> header;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) {
      std::stringstream ss(line);
      for (std::string c; std::getline(ss, c, ',');) header.push_back(c);
    } else {
      ++rows;
    }
  }
  return {header, rows};
}

bool has(const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); }

using test::edit;
using test::expect_config_error;

}  // namespace

TEST_F(HalfCarRig, RunFastWritesTheHalfCarColumns) {
  const auto r = run_command(kRigctl + " run " + kConfig + " --fast --no-realtime --log " + path("run.lcm") +
                             " --csv " + path("run.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("half_car"), std::string::npos);
  const auto [header, rows] = csv_shape(path("run.csv"));
  EXPECT_EQ(rows, 4000);  // 10 s at 2.5 ms
  for (const char* col : {"t", "z_s_ref", "z_r1", "z_r2", "z_s", "phi", "z_u1", "z_u2", "f_1", "f_2"}) {
    EXPECT_TRUE(has(header, col)) << col;
  }
  EXPECT_NE(read_file(path("run.csv")).find("# rig: half_car"), std::string::npos);
}

TEST_F(HalfCarRig, CompareReportsOursBesideThePapersAndTheIssuesClaimsHold) {
  const auto r = run_command(kRigctl + " compare " + kConfig + " --out " + path("cmp"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::printf("%s\n", r.output.c_str());
  // The paper's figures, printed beside ours, and the account of differences.
  for (const char* s : {"74.2 %", "88.72 %", "28.5 %", "6 -> 3.5 s", "peak body displacement", "peak body acceleration",
                        "settling time", "Why our figures differ", "passive", "fuzzy", "skyhook", "lqr"}) {
    EXPECT_NE(r.output.find(s), std::string::npos) << s;
  }
  // Each run's CSV in the run-file format.
  for (const char* run : {"passive", "fuzzy", "skyhook", "lqr"}) {
    const auto [header, rows] = csv_shape(path(std::string("cmp/") + run + ".csv"));
    EXPECT_EQ(rows, 4000) << run;
    for (const char* col : {"t", "z_r1", "z_r2", "z_s", "phi", "z_u1", "z_u2", "f_1", "f_2"}) {
      EXPECT_TRUE(has(header, col)) << run << ": " << col;
    }
  }
  // The issue's assertions, on the report's own numbers.
  const YAML::Node m = YAML::LoadFile(path("cmp/metrics.json"));
  const YAML::Node runs = m["runs"];
  const YAML::Node passive = runs["passive"], fuzzy = runs["fuzzy"];
  EXPECT_LT(fuzzy["peak_z_s_m"].as<double>(), passive["peak_z_s_m"].as<double>());
  EXPECT_LT(fuzzy["peak_acc_m_s2"].as<double>(), passive["peak_acc_m_s2"].as<double>());
  EXPECT_LT(fuzzy["settling_time_s"].as<double>(), passive["settling_time_s"].as<double>());
  EXPECT_TRUE(fuzzy["settled"].as<bool>());
  EXPECT_TRUE(passive["settled"].as<bool>());
  const double limit = m["force_limit_n"].as<double>();
  EXPECT_DOUBLE_EQ(limit, 2000.0);
  bool contact_kept = true;
  for (const char* name : {"passive", "fuzzy", "skyhook", "lqr"}) {
    const YAML::Node run = runs[name];
    EXPECT_EQ(run["final_state"].as<std::string>(), "stopped") << name;
    for (int i = 0; i < 2; ++i) {
      EXPECT_LE(run["peak_force_n"][i].as<double>(), limit) << name;
      EXPECT_LE(run["peak_applied_force_n"][i].as<double>(), limit) << name;
      contact_kept = contact_kept && run["time_without_contact_s"][i].as<double>() == 0.0;
    }
  }
  EXPECT_EQ(passive["peak_force_n"][0].as<double>(), 0.0);
  EXPECT_GT(fuzzy["peak_force_n"][0].as<double>(), 0.0);
  // On the paper's bump every tyre keeps contact, and the report says so
  // (were it lost, the report would have to say that instead).
  EXPECT_TRUE(contact_kept);
  EXPECT_NE(r.output.find(contact_kept ? "Tyre contact: kept" : "Tyre contact LOST"), std::string::npos);
  // Our reductions are in the JSON beside the paper's.
  EXPECT_GT(m["reductions_percent"]["fuzzy"]["peak_body_displacement"].as<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["paper"]["peak_body_displacement_reduction_percent"].as<double>(), 74.2);
}

TEST_F(HalfCarRig, CompareRunsTheRollPlaneAndTheOtherRoads) {
  for (const char* c : {"roll_curve", "one_wheel", "single_hump"}) {
    const auto r = run_command(kRigctl + " compare " + kConfig + " --case " + c + " --out " + path(c));
    ASSERT_EQ(r.exit_code, 0) << c << ": " << r.output;
    const YAML::Node m = YAML::LoadFile(path(std::string(c) + "/metrics.json"));
    EXPECT_EQ(m["plane"].as<std::string>(), std::string(c) == "single_hump" ? "pitch" : "roll") << c;
    for (const char* name : {"fuzzy", "skyhook", "lqr"}) {
      EXPECT_LE(m["runs"][name]["peak_force_n"][0].as<double>(), 2000.0) << c << " " << name;
    }
  }
  // The roll moment of the curve rolls the passive body outwards: about
  // 36 mrad at steady state (2160 N m on springs and tyres in series).
  const YAML::Node curve = YAML::LoadFile(path("roll_curve/metrics.json"));
  EXPECT_GT(curve["runs"]["passive"]["peak_phi_rad"].as<double>(), 0.03);
}

TEST_F(HalfCarRig, OptimizeImprovesTheCostWithinTheBounds) {
  const auto r = run_command(kRigctl + " optimize " + kConfig + " --evaluations 20 --out " + path("opt.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::printf("%s\n", r.output.c_str());
  // The progress display (stderr, merged here).
  EXPECT_NE(r.output.find("evaluations, best cost"), std::string::npos);
  EXPECT_NE(r.output.find("elapsed"), std::string::npos);
  const YAML::Node o = YAML::LoadFile(path("opt.json"));
  EXPECT_EQ(o["evaluations"].as<int>(), 20);
  const double initial = o["initial"]["cost"].as<double>();
  const double best = o["optimum"]["cost"].as<double>();
  EXPECT_NEAR(initial, 1.75, 1e-9);  // the sum of the weights: the initial design is the reference
  EXPECT_LT(best, initial);
  EXPECT_TRUE(o["optimum"]["feasible"].as<bool>());
  EXPECT_TRUE(o["within_bounds"].as<bool>());
  EXPECT_LE(o["optimum"]["peak_suspension_travel_m"].as<double>(), o["travel_limit_m"].as<double>());
  int checked = 0;
  for (const auto& kv : o["bounds"]) {
    const std::string name = kv.first.as<std::string>();
    const double lo = kv.second[0].as<double>(), hi = kv.second[1].as<double>();
    const double v = o["optimum"]["parameters"][name].as<double>();
    EXPECT_GE(v, lo) << name;
    EXPECT_LE(v, hi) << name;
    ++checked;
  }
  EXPECT_EQ(checked, 4);
  // Table 2's bounds as configured.
  EXPECT_DOUBLE_EQ(o["bounds"]["spring_1"][0].as<double>(), 75000.0);
  EXPECT_DOUBLE_EQ(o["bounds"]["spring_2"][1].as<double>(), 70000.0);
  EXPECT_DOUBLE_EQ(o["bounds"]["damper_1"][0].as<double>(), 875.0);
}

TEST_F(HalfCarRig, OptimizeRefusesAnInitialDesignOutsideItsBounds) {
  const std::string yaml =
      edit(read_file(kConfig), "    spring_1: \\[75000.0, 100000.0\\]", "    spring_1: [90000.0, 100000.0]");
  std::ofstream(path("bad.yaml")) << yaml;
  const auto r = run_command(kRigctl + " optimize " + path("bad.yaml") + " --evaluations 2 --out " + path("o.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("plant.corner_1.spring_n_per_m"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("optimize.variables.spring_1"), std::string::npos) << r.output;
}

TEST(HalfCarConfig, ShippedConfigLoadsWithTheProposedHalfCar) {
  const auto c = load_rig_config(kConfig);
  EXPECT_EQ(c.rig, RigKind::kHalfCar);
  EXPECT_EQ(c.controller.type, ControllerKind::kFuzzy);
  EXPECT_EQ(c.half_car.plane, HalfCarPlane::kPitch);
  EXPECT_DOUBLE_EQ(c.half_car.mass_body, 1080.0);
  EXPECT_DOUBLE_EQ(c.half_car.spring_1, 80000.0);
  EXPECT_DOUBLE_EQ(c.half_car.spring_2, 45000.0);
  EXPECT_DOUBLE_EQ(c.half_car.road.bump.amplitude, 0.05);
  EXPECT_DOUBLE_EQ(c.half_car.road.bump.wavelength, 0.20);
  EXPECT_DOUBLE_EQ(c.half_car.speed, 20.0);
  EXPECT_DOUBLE_EQ(c.suspension_report.settling_band_fraction, 0.05);  // per cent converted
  EXPECT_EQ(c.profile.type, ProfileKind::kHold);
  for (const ControllerKind type : suspension_controllers()) {
    RigConfig k = c;
    k.controller.type = type;
    const AssembledRig rig = assemble_rig(k);
    EXPECT_EQ(rig.controller->name(), to_string(type));
    EXPECT_EQ(rig.setpoint_name, "z_s_ref");
    EXPECT_DOUBLE_EQ(rig.profile_duration_s, 10.0);
  }
}

TEST(HalfCarConfig, EveryCaseLoadsAndAssemblesEveryController) {
  const auto names = config_case_names(kConfig);
  for (const char* expected : {"roll_curve", "one_wheel", "iso_c", "single_hump", "fuzzy_odd", "paper_bump"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  for (const auto& name : names) {
    const auto c = load_rig_config(kConfig, name);
    for (const ControllerKind type : suspension_controllers()) {
      RigConfig k = c;
      k.controller.type = type;
      EXPECT_NO_THROW(assemble_rig(k)) << name << " " << type;
    }
  }
  const auto roll = load_rig_config(kConfig, "roll_curve");
  EXPECT_EQ(roll.half_car.plane, HalfCarPlane::kRoll);
  EXPECT_DOUBLE_EQ(roll.half_car.curve_radius, 100.0);
  EXPECT_DOUBLE_EQ(roll.half_car.inertia_body, 473.0);
  EXPECT_EQ(roll.half_car.road.kind, RoadKind::kFlat);
  const auto one = load_rig_config(kConfig, "one_wheel");
  EXPECT_EQ(one.half_car.road.wheels, RoadWheels::kWheel2);
  const auto iso = load_rig_config(kConfig, "iso_c");
  EXPECT_EQ(iso.half_car.road.kind, RoadKind::kIso8608);
  EXPECT_EQ(iso.half_car.road.iso.road_class, IsoRoadClass::kC);
}

// The fuzzy engine written out in the config is the paper's controller of
// rt/control/fuzzy_engine.hpp: same sets, same rules, same outputs.
TEST(HalfCarConfig, ConfiguredFuzzyEngineIsThePapersController) {
  auto same = [](const FuzzyEngineSpec& a, const FuzzyEngineSpec& b) {
    ASSERT_EQ(a.inputs.size(), b.inputs.size());
    for (std::size_t i = 0; i < a.inputs.size(); ++i) {
      const auto& x = a.inputs[i];
      const auto& y = b.inputs[i];
      EXPECT_DOUBLE_EQ(x.min, y.min);
      EXPECT_DOUBLE_EQ(x.max, y.max);
      EXPECT_NEAR(x.scale, y.scale, 1e-12 * y.scale);
      ASSERT_EQ(x.sets.size(), y.sets.size());
      for (std::size_t k = 0; k < x.sets.size(); ++k) {
        EXPECT_EQ(x.sets[k].name, y.sets[k].name);
        EXPECT_EQ(x.sets[k].shape, y.sets[k].shape);
        EXPECT_EQ(x.sets[k].points, y.sets[k].points) << x.sets[k].name;
      }
    }
    EXPECT_DOUBLE_EQ(a.output.scale, b.output.scale);
    ASSERT_EQ(a.output.sets.size(), b.output.sets.size());
    for (std::size_t k = 0; k < a.output.sets.size(); ++k) EXPECT_EQ(a.output.sets[k].points, b.output.sets[k].points);
    ASSERT_EQ(a.rules.size(), b.rules.size());
    for (std::size_t r = 0; r < a.rules.size(); ++r) {
      EXPECT_EQ(a.rules[r].antecedents, b.rules[r].antecedents) << "rule " << r + 1;
      EXPECT_EQ(a.rules[r].consequent, b.rules[r].consequent) << "rule " << r + 1;
    }
    FuzzyEngine ea(a), eb(b);
    for (double v = -0.15; v <= 0.15; v += 0.0125) {
      for (double acc = -5.0; acc <= 5.0; acc += 0.625) {
        const std::array<double, 2> in{v, acc};
        EXPECT_NEAR(ea.evaluate(in), eb.evaluate(in), 1e-9) << v << " " << acc;
      }
    }
  };
  const auto c = load_rig_config(kConfig);
  same(c.controller.suspension.fuzzy, paper_fuzzy_spec({0.10, 4.0, 2000.0}));
  EXPECT_EQ(c.controller.suspension.fuzzy_first_input, FuzzyFirstInput::kVelocity);
  // Rule 1 (NVL, N) -> NVL and rule 15 (PS, ZE) -> PS, numbered as the paper does.
  EXPECT_EQ(c.controller.suspension.fuzzy.rules[0].consequent, "NVL");
  EXPECT_EQ(c.controller.suspension.fuzzy.rules[14].antecedents, (std::vector<std::string>{"PS", "ZE"}));
  EXPECT_EQ(c.controller.suspension.fuzzy.rules[14].consequent, "PS");
  const auto odd = load_rig_config(kConfig, "fuzzy_odd");
  same(odd.controller.suspension.fuzzy, paper_fuzzy_spec({0.10, 4.0, 2000.0}, PaperRuleTable::kOddSymmetric));
}

TEST(HalfCarConfig, TheEngineIsConfigurable) {
  // A different rule base and scaling from the config changes the law.
  std::string yaml = read_file(kConfig);
  yaml = edit(yaml, "      ZE: \"ZE ZE ZE\"", "      ZE: \"PS ZE NS\"");
  yaml = edit(yaml, "        scale: 2000.0 ", "        scale: 1500.0 ");
  const auto c = parse_rig_config(yaml, "edited.yaml");
  FuzzyEngine configured(c.controller.suspension.fuzzy);
  FuzzyEngine paper(paper_fuzzy_spec({0.10, 4.0, 2000.0}));
  const std::array<double, 2> at_rest_decelerating{0.0, -4.0};  // x1 ZE, x2 N
  EXPECT_NEAR(paper.evaluate(at_rest_decelerating), 0.0, 1e-6);
  EXPECT_NEAR(configured.evaluate(at_rest_decelerating), 0.2 * 1500.0, 1.0);  // PS peak at 0.2 of 1500 N
  EXPECT_DOUBLE_EQ(c.controller.suspension.fuzzy.output.scale, 1500.0);
}

TEST(HalfCarConfig, HoldProfileIsAConstant) {
  HoldProfile hold(0.0125, 3.0);
  EXPECT_DOUBLE_EQ(hold.at(0.0), 0.0125);
  EXPECT_DOUBLE_EQ(hold.at(100.0), 0.0125);
  EXPECT_DOUBLE_EQ(hold.duration(), 3.0);
}

TEST(HalfCarConfig, BadKeysGiveClearErrorsNamingTheKey) {
  const std::string shipped = read_file(kConfig);
  expect_config_error(edit(shipped, "    spring_n_per_m: 80000.0 ", "    spring_rate: 80000.0\n    spring_n_per_m: 80000.0 "),
               {"bad.yaml:", "plant.corner_1.spring_rate", "unknown key"});
  expect_config_error(edit(shipped, "    spring_n_per_m: 80000.0 ", "    spring_rate: 80000.0 "),
               {"bad.yaml:", "plant.corner_1.spring_n_per_m", "missing required key"});
  expect_config_error(edit(shipped, "    damper_n_s_per_m: 1500.0 # Table 2 C1[^\n]*\n", ""),
               {"bad.yaml:", "plant.corner_1.damper_n_s_per_m", "missing required key"});
  expect_config_error(edit(shipped, "  plane: pitch ", "  plane: yaw "), {"plant.plane", "unknown value 'yaw'", "pitch, roll"});
  expect_config_error(edit(shipped, "    kind: bump ", "    kind: cobbles "), {"plant.road.kind", "unknown value 'cobbles'"});
  expect_config_error(edit(shipped, "      class: C ", "      class: F "), {"plant.road.iso8608.class", "'F'"});
  expect_config_error(edit(shipped, "      amplitude_m: 0.05 ", "      amplitude_m: -0.05 "),
               {"plant.road.bump.amplitude_m", "got -0.05"});
  expect_config_error(edit(shipped, "  vehicle_speed_m_s: 20.0 ", "  vehicle_speed_m_s: fast "),
               {"plant.vehicle_speed_m_s", "expected a number", "'fast'"});
  expect_config_error(edit(shipped, "  type: fuzzy ", "  type: pid "), {"controller.type", "unknown controller 'pid'", "skyhook"});
  expect_config_error(edit(shipped, "  force_limit_n: 2000.0", "  force_limit_n: 8000.0"),
               {"controller.force_limit_n", "outputs.f_1.range"});
  expect_config_error(edit(shipped, "  output_2: f_2 ", "  output_2: f_9 "), {"controller.output_2", "unknown output channel 'f_9'"});
  expect_config_error(edit(shipped, "      NS: \"NM NS NS\"", "      NS: \"NM NS NX\""),
               {"controller.fuzzy.rules.NS", "unknown output set 'NX'"});
  expect_config_error(edit(shipped, "      NS: \"NM NS NS\"", "      NS: \"NM NS\""), {"controller.fuzzy.rules.NS", "expected 3"});
  expect_config_error(edit(shipped, "      NS: \"NM NS NS\"\n", ""), {"controller.fuzzy.rules.NS", "missing required key"});
  expect_config_error(edit(shipped, "          NL: \\{triangle: \\[-0.8, -0.6, -0.4\\]\\}", "          NL: {triangle: [-0.4, -0.6, -0.8]}"),
               {"controller.fuzzy.inputs.velocity_error.sets.NL.triangle"});
  expect_config_error(edit(shipped, "          NL: \\{triangle: \\[-0.8, -0.6, -0.4\\]\\}", "          NL: {triangle: [-0.8, -0.6]}"),
               {"controller.fuzzy.inputs.velocity_error.sets.NL.triangle", "expected 3 numbers"});
  expect_config_error(edit(shipped, "          NL: \\{triangle: \\[-0.8, -0.6, -0.4\\]\\}", "          NL: {bell: [-0.8, -0.6, -0.4]}"),
               {"controller.fuzzy.inputs.velocity_error.sets.NL", "exactly one shape"});
  expect_config_error(edit(shipped, "    c_sky_n_s_per_m: 4000.0", "    c_sky_n_s_per_m: 4000.0\n    c_sky: 4000.0"),
               {"controller.skyhook.c_sky", "unknown key"});
  expect_config_error(edit(shipped, "    angle_rad: 0.03", "    angle_rad: 0"), {"controller.lqr.angle_rad"});
  expect_config_error(edit(shipped, "  duration_s: 10.0 ", "  length_s: 10.0 "), {"profile.duration_s", "missing required key"});
  expect_config_error(edit(shipped, "    spring_1: \\[75000.0, 100000.0\\]", "    mass_body: [500.0, 1500.0]"),
               {"optimize.variables.mass_body", "unknown design variable"});
  expect_config_error(edit(shipped, "  algorithm: crs2_lm ", "  algorithm: genetic "), {"optimize.algorithm", "isres"});
  expect_config_error(edit(shipped, "  settling_band_percent: 5.0", "  settling_band_percent: 150"),
               {"report.settling_band_percent", "got 150"});
  expect_config_error(edit(shipped, "  z_s_ddot: \\{", "  z_s_dddot: {"), {"sensors.z_s_dddot"});
}

TEST_F(HalfCarRig, BadConfigStopsTheProgramsWithExitCode2) {
  std::ofstream(path("bad.yaml")) << edit(read_file(kConfig), "  plane: pitch ", "  plane: yaw ");
  for (const char* cmd : {" run ", " compare ", " optimize "}) {
    const auto r = run_command(kRigctl + cmd + path("bad.yaml") + (std::string(cmd) == " run " ? " --fast" : ""));
    EXPECT_EQ(r.exit_code, 2) << cmd << r.output;
    EXPECT_NE(r.output.find("plant.plane"), std::string::npos) << cmd << r.output;
  }
  // compare and optimize are for the half car only.
  const auto q = run_command(kRigctl + " compare " + std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml --out " +
                             path("q"));
  EXPECT_EQ(q.exit_code, 2) << q.output;
  EXPECT_NE(q.output.find("half_car"), std::string::npos) << q.output;
}
