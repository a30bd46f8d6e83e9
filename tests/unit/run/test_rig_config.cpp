// Bad config never starts a rig: each kind of mistake gives its own error
// naming the file, the key and the reason.
#include <gtest/gtest.h>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "tools/run/rig_assembly.hpp"

using namespace rigctl;

namespace {
using test::edit;
using test::expect_config_error;
using test::shipped_config;
}  // namespace

TEST(RigConfig, ShippedConfigLoadsWithThePapersModel) {
  const auto c = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
  EXPECT_EQ(c.rig, RigKind::kQuarterCar);
  EXPECT_EQ(c.driver, DriverKind::kSim);
  EXPECT_EQ(c.controller.type, ControllerKind::kPi);
  EXPECT_EQ(c.profile.type, ProfileKind::kRampSteps);
  EXPECT_TRUE(c.quarter_car.bearing_friction.enabled);
  EXPECT_NEAR(c.quarter_car.bearing_friction.construction_angle, 62.0 * M_PI / 180.0, 1e-12);  // degrees converted
  EXPECT_DOUBLE_EQ(c.loop.period_s, 0.0025);
  ASSERT_EQ(c.profile.steps.size(), 4u);
  EXPECT_DOUBLE_EQ(c.profile.steps[0], 0.05);
  EXPECT_EQ(c.sensors.size(), 8u);
  EXPECT_NO_THROW(assemble_rig(c));
}

TEST(RigConfig, UnknownKey) {
  expect_config_error(edit(shipped_config(), "  kp: 80.0", "  kp: 80.0\n  kd: 1.0"),
               {"bad.yaml:", "controller.kd", "unknown key"});
}

TEST(RigConfig, MissingKey) {
  expect_config_error(edit(shipped_config(), "  ki: 60.0[^\n]*\n", ""), {"bad.yaml:", "controller.ki", "missing required key"});
}

TEST(RigConfig, WrongType) {
  expect_config_error(edit(shipped_config(), "  period_s: 0.0025", "  period_s: fast"),
               {"bad.yaml:", "loop.period_s", "expected a number", "'fast'"});
  expect_config_error(edit(shipped_config(), "    leakage: true", "    leakage: maybe"),
               {"plant.hydraulics.leakage", "expected true or false"});
}

TEST(RigConfig, OutOfRange) {
  expect_config_error(edit(shipped_config(), "  period_s: 0.0025", "  period_s: 5"),
               {"bad.yaml:", "loop.period_s", "must be in [0.0001, 0.1]", "got 5"});
  expect_config_error(edit(shipped_config(), "    construction_angle_deg: 62.0", "    construction_angle_deg: 95"),
               {"plant.bearing_friction.construction_angle_deg", "got 95"});
}

// The run catalog's section is optional and read strictly (docs/rig-health.md 1).
TEST(RigConfig, CatalogSectionIsOptionalAndStrict) {
  EXPECT_FALSE(parse_rig_config(shipped_config(), "ok.yaml").catalog);
  const std::string with = shipped_config() + "\ncatalog:\n  path: runs/catalog.sqlite\n  rig_name: qc-3\n";
  const auto c = parse_rig_config(with, "ok.yaml");
  ASSERT_TRUE(c.catalog);
  EXPECT_EQ(c.catalog->path, "runs/catalog.sqlite");
  EXPECT_EQ(c.catalog->rig_name, "qc-3");
  EXPECT_EQ(parse_rig_config(shipped_config() + "\ncatalog:\n  path: c.sqlite\n", "ok.yaml").catalog->rig_name, "");
  expect_config_error(shipped_config() + "\ncatalog:\n  path: c.sqlite\n  rig: qc-3\n", {"bad.yaml:", "catalog.rig", "unknown key"});
  expect_config_error(shipped_config() + "\ncatalog:\n  rig_name: qc-3\n", {"bad.yaml:", "catalog.path", "missing required key"});
}

// The PI's velocity feedforward is optional (a tuned config has it) and
// checked like every gain.
TEST(RigConfig, VelocityFeedforwardIsOptionalAndChecked) {
  EXPECT_DOUBLE_EQ(parse_rig_config(shipped_config(), "ok.yaml").controller.pi.velocity_feedforward, 0.0);
  const auto c = parse_rig_config(edit(shipped_config(), "  kp: 80.0", "  velocity_feedforward: 3.5\n  kp: 80.0"), "ok.yaml");
  EXPECT_DOUBLE_EQ(c.controller.pi.velocity_feedforward, 3.5);
  expect_config_error(edit(shipped_config(), "  kp: 80.0", "  velocity_feedforward: -1\n  kp: 80.0"),
                      {"bad.yaml:", "controller.velocity_feedforward", "got -1"});
}

TEST(RigConfig, LineNumberPointsAtTheBadValue) {
  const std::string yaml = edit(shipped_config(), "  period_s: 0.0025", "  period_s: -1");
  expect_config_error(yaml, {"bad.yaml:" + std::to_string(test::line_of(yaml, "period_s: -1")) + ":"});
}

TEST(RigConfig, UnknownChannelNames) {
  expect_config_error(edit(shipped_config(), "  feedback: x_r", "  feedback: x_q"),
               {"controller.feedback", "unknown input channel 'x_q'", "x_r"});
  expect_config_error(edit(shipped_config(), "  x_r: \\[-0.012, 0.172\\]", "  x_z: [-0.012, 0.172]"), {"limits.x_z"});
  expect_config_error(edit(shipped_config(), "  f_t: \\{", "  f_z: {"), {"sensors.f_z"});
}

TEST(RigConfig, SyntaxErrorNamesTheLine) {
  expect_config_error(edit(shipped_config(), "  kp: 80.0", "  kp: [80.0"), {"bad.yaml:", "YAML syntax error"});
}

TEST(RigConfig, MissingFile) {
  try {
    load_rig_config("/nonexistent/rig.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/rig.yaml"), std::string::npos);
  }
}

TEST(RigConfig, CasesMergeOverTheFileAndUnknownCasesAreNamed) {
  // The shipped cases replaced by the test's own.
  const std::string shipped = shipped_config();
  const std::string yaml = shipped.substr(0, shipped.find("\ncases:")) + R"(
cases:
  soft: {controller: {kp: 40.0}, plant: {bearing_friction: {enabled: false}}}
  broken: {controller: {kq: 1.0}}
)";
  const auto base = parse_rig_config(yaml, "c.yaml");
  EXPECT_DOUBLE_EQ(base.controller.pi.kp, 80.0);
  EXPECT_TRUE(base.quarter_car.bearing_friction.enabled);
  const auto soft = parse_rig_config(yaml, "c.yaml", "soft");
  EXPECT_DOUBLE_EQ(soft.controller.pi.kp, 40.0);
  EXPECT_DOUBLE_EQ(soft.controller.pi.ki, 60.0) << "keys the case does not name are kept";
  EXPECT_FALSE(soft.quarter_car.bearing_friction.enabled);
  EXPECT_DOUBLE_EQ(soft.quarter_car.bearing_friction.coulomb_base, 40.0);
  try {
    parse_rig_config(yaml, "c.yaml", "hard");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("no case 'hard' (cases: soft, broken)"), std::string::npos) << e.what();
  }
  try {
    parse_rig_config(yaml, "c.yaml", "broken");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.kq: unknown key"), std::string::npos) << e.what();
  }
}

TEST(RigConfig, PneumaticConfigAndEveryPaperCaseLoad) {
  const std::string path = std::string(RIGCTL_SOURCE_DIR) + "/config/pneumatic_rotary.yaml";
  const auto c = load_rig_config(path);
  EXPECT_EQ(c.rig, RigKind::kPneumaticRotary);
  EXPECT_EQ(c.controller.type, ControllerKind::kPvp);
  EXPECT_DOUBLE_EQ(c.pneumatic_rotary.hysteresis.level, 0.02);  // per cent converted
  EXPECT_EQ(c.dacs.at("u").bits, 12);
  const auto names = config_case_names(path);
  EXPECT_GE(names.size(), 10u);
  for (const auto& name : names) EXPECT_NO_THROW(load_rig_config(path, name)) << name;
  const auto fig7 = load_rig_config(path, "fig7");
  EXPECT_DOUBLE_EQ(fig7.controller.pvp.kp, 1.7e-5) << "V/bar converted to V/Pa";
  const auto fig4e = load_rig_config(path, "fig4e");
  EXPECT_DOUBLE_EQ(fig4e.pneumatic_rotary.inertia, 0.4);
}

namespace rigctl {
namespace {

// The quarter car's `diagnosis` case turns the ramp_steps profile into a
// demand table: a case that changes a section's type replaces the section
// (merged key by key, the ramp keys would be unknown to a csv profile).
TEST(RigConfigCases, ACaseThatChangesASectionsTypeReplacesTheSection) {
  const RigConfig c = load_rig_config(RIGCTL_SOURCE_DIR "/config/quarter_car.yaml", "diagnosis");
  EXPECT_EQ(c.profile.type, ProfileKind::kCsv);
  EXPECT_NE(c.profile.csv_file.find("quarter_car_diagnosis_demand.csv"), std::string::npos) << c.profile.csv_file;
  EXPECT_EQ(c.profile.csv_column, "x_ref");
  EXPECT_TRUE(c.profile.steps.empty());
}

}  // namespace
}  // namespace rigctl
