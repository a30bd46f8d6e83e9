// `rigctl rainflow` on recorded runs: the ASTM E1049 worked example as a run
// file, and a run's LCM log counted like the CSV of the same run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "process.hpp"
#include "read_file.hpp"

using namespace rigctl;

namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string line_with(const std::string& text, const std::string& start) {
  const auto at = text.find(start);
  return at == std::string::npos ? "" : text.substr(at, text.find('\n', at) - at);
}

}  // namespace

// ASTM E1049 Fig. 6: 4 cycles in all (0.5 + 1.5 + 0.5 + 1.0 + 0.5), the
// largest range 9 a half cycle; with reference range 1 and exponent 1 the
// pseudo-damage is the sum of count x range: 0.5*3 + 1.5*4 + 0.5*6 + 1*8 + 0.5*9 = 23.
TEST(RainflowCommand, CountsTheAstmExampleFromARunFile) {
  const auto dir = scratch("rainflow-astm");
  {
    std::ofstream f(dir / "astm.csv");
    f << "t,load\n";
    const double load[] = {-2, 1, -3, 5, -1, 3, -4, 4, -2};
    for (int i = 0; i < 9; ++i) f << i * 0.1 << "," << load[i] << "\n";
  }
  const auto r = test::run_command(std::string(RIGCTL_BINARY) + " rainflow " + (dir / "astm.csv").string() +
                                   " --channel load --basquin 1 --reference-range 1 --matrix " + (dir / "m.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("9 samples, 4 cycles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pseudo-damage 23 "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("largest ranges: 9 (half) 8 (half) 8 (half) 6 (half) 4"), std::string::npos) << r.output;
  const std::string m = test::read_file((dir / "m.csv").string());
  EXPECT_NE(m.find("# cycles: 4\n"), std::string::npos) << m;
  EXPECT_NE(m.find("range,mean,cycles\n"), std::string::npos) << m;
  const auto missing = test::run_command(std::string(RIGCTL_BINARY) + " rainflow " + (dir / "astm.csv").string() + " --channel force");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("has no channel 'force' (columns: t, load)"), std::string::npos) << missing.output;
}

TEST(RainflowCommand, ARunsLogCountsAsItsCsv) {
  const auto dir = scratch("rainflow-log");
  const std::string log = (dir / "run.lcm").string(), csv = (dir / "run.csv").string();
  const auto run = test::run_command(std::string(RIGCTL_BINARY) + " run " + RIGCTL_SOURCE_DIR +
                                     "/config/quarter_car.yaml --fast --no-realtime --duration 8 --log " + log + " --csv " + csv);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto from_log = test::run_command(std::string(RIGCTL_BINARY) + " rainflow " + log + " --channel x_r");
  const auto from_csv = test::run_command(std::string(RIGCTL_BINARY) + " rainflow " + csv + " --channel x_r");
  ASSERT_EQ(from_log.exit_code, 0) << from_log.output;
  ASSERT_EQ(from_csv.exit_code, 0) << from_csv.output;
  EXPECT_EQ(line_with(from_log.output, "  pseudo-damage"), line_with(from_csv.output, "  pseudo-damage"));
  EXPECT_FALSE(line_with(from_log.output, "  pseudo-damage").empty()) << from_log.output;
  EXPECT_EQ(line_with(from_log.output, "  largest"), line_with(from_csv.output, "  largest"));
}
