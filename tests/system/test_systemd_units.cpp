// Deployment: `cmake --install` into a temporary prefix puts the program, the
// units and the configs in place, with the controller's unit naming that
// prefix and running in operator mode (never auto-starting the rig); the
// installed program in operator mode with no operator stays faulted; both
// units score 2.0 or better in `systemd-analyze security --offline=true`.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "process.hpp"
#include "read_file.hpp"

namespace fs = std::filesystem;
using rigctl::test::run_command;

namespace {

using rigctl::test::read_file;

class InstalledTree : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    prefix_ = fs::temp_directory_path() / ("rigctl_install_" + std::to_string(::getpid()));
    fs::remove_all(prefix_);
    install_ = run_command("cmake --install '" + std::string(RIGCTL_BUILD_DIR) + "' --prefix '" + prefix_.string() + "'");
  }
  static void TearDownTestSuite() { fs::remove_all(prefix_); }
  void SetUp() override { ASSERT_EQ(install_.exit_code, 0) << install_.output; }

  static inline fs::path prefix_;
  static inline rigctl::test::ProcessResult install_;
};

TEST_F(InstalledTree, PutsProgramUnitsAndConfigsInPlace) {
  const fs::path bin = prefix_ / "bin/rigctl";
  ASSERT_TRUE(fs::exists(bin));
  EXPECT_EQ(::access(bin.c_str(), X_OK), 0);
  for (const char* f : {"lib/systemd/system/rigctl.service", "lib/systemd/system/lcm-logger.service",
                        "etc/rigctl/quarter_car.yaml", "etc/rigctl/pneumatic_rotary.yaml", "etc/rigctl/half_car.yaml",
                        "share/doc/rigctl/deployment.md"}) {
    EXPECT_TRUE(fs::is_regular_file(prefix_ / f)) << f;
  }
  const auto version = run_command(bin.string() + " --version");
  EXPECT_EQ(version.exit_code, 0) << version.output;
}

TEST_F(InstalledTree, ControllerUnitNamesThePrefixAndRunsInOperatorMode) {
  const std::string unit = read_file(prefix_ / "lib/systemd/system/rigctl.service");
  EXPECT_EQ(unit.find("@RIGCTL_"), std::string::npos) << "placeholder left in the unit";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(unit, m, std::regex("\nExecStart=(\\S+) run ([^\n]*)"))) << unit;
  EXPECT_EQ(m[1].str(), (prefix_ / "bin/rigctl").string());
  // --operator: safety.auto_sequence is false for the service whatever the
  // file says, so a restart never starts the rig.
  EXPECT_NE(m[2].str().find("--operator"), std::string::npos) << m[2];
  EXPECT_NE(unit.find("RIGCTL_CONFIG=" + (prefix_ / "etc/rigctl/quarter_car.yaml").string()), std::string::npos);
  EXPECT_NE(unit.find("LoadCredential=operator.key:" + (prefix_ / "etc/rigctl/operator.key").string()), std::string::npos);
  for (const char* key : {"\nType=notify\n", "\nWatchdogSec=", "\nRestart=on-failure\n", "\nLimitRTPRIO=", "\nLimitMEMLOCK=infinity\n"}) {
    EXPECT_NE(unit.find(key), std::string::npos) << key;
  }
}

TEST_F(InstalledTree, ServiceCommandLineWithoutAnOperatorStaysFaulted) {
  // What the unit runs, against the installed config, with no operator: the
  // rig never leaves `faulted` (no state change at all) and nothing drives the valve.
  const fs::path key = prefix_ / "operator.key";
  std::ofstream(key) << std::string(32, 'k');
  fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  const fs::path log = prefix_ / "run.lcm";
  const auto r = run_command((prefix_ / "bin/rigctl").string() + " run --operator --key " + key.string() + " " +
                             (prefix_ / "etc/rigctl/quarter_car.yaml").string() + " --fast --duration 1 --log " + log.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rig state faulted"), std::string::npos) << r.output;
  const std::string events = read_file(log.string() + ".events");
  EXPECT_NE(events.find("code=run_started"), std::string::npos) << events;
  EXPECT_EQ(events.find("code=state_changed"), std::string::npos) << events;
}

// `systemd-analyze security --offline=true UNIT`: "Overall exposure level for
// UNIT: 1.6 OK". -1 when it cannot run here.
double exposure(const fs::path& unit, std::string& output) {
  const auto r = run_command("cd '" + unit.parent_path().string() + "' && systemd-analyze security --offline=true '" +
                             unit.string() + "'");
  output = r.output;
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("Overall exposure level for [^:]+: ([0-9.]+)"))) return -1.0;
  return std::stod(m[1]);
}

TEST_F(InstalledTree, UnitsExposureIsAtMostTwo) {
  if (run_command("systemd-analyze --version").exit_code != 0) GTEST_SKIP() << "no systemd-analyze (package systemd)";
  for (const char* name : {"rigctl.service", "lcm-logger.service"}) {
    std::string out;
    const double e = exposure(prefix_ / "lib/systemd/system" / name, out);
    if (e < 0 && out.find("offline") != std::string::npos) GTEST_SKIP() << "systemd-analyze without --offline: " << out;
    ASSERT_GE(e, 0.0) << out;
    EXPECT_LE(e, 2.0) << name << "\n" << out;
  }
}

}  // namespace
