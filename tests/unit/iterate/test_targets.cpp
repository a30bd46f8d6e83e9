// Targets: read from a run file (other columns ignored, errors naming line
// and column) or an RPC III file, on the loop's period; and the road target
// generator (a quarter car's wheel over an ISO 8608 road).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "config/rig_config.hpp"
#include "tools/iterate/road_target.hpp"
#include "tools/iterate/rpc3_file.hpp"
#include "tools/iterate/spectrum.hpp"
#include "tools/iterate/target_file.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

std::string temp_path(const std::string& name) { return (std::filesystem::path(::testing::TempDir()) / name).string(); }

std::string write(const std::string& name, const std::string& text) {
  const std::string p = temp_path(name);
  std::ofstream(p) << text;
  return p;
}

std::string table(const std::string& bad_cell_row = "") {
  std::string s = "# rig: quarter_car\nt,notes,x_w,x_r\n";
  for (int i = 0; i < 40; ++i) {
    s += std::to_string(i * 0.0025) + ",text" + std::to_string(i) + "," +
         (std::to_string(i) == bad_cell_row ? std::string("nan") : std::to_string(0.08 + 0.001 * i)) + ",0.08\n";
  }
  return s;
}

TEST(TargetFile, TakesTheChannelAndIgnoresOtherColumns) {
  const auto x = read_target(write("t_ok.csv", table()), "x_w", 0.0025, 600.0).values;
  ASSERT_EQ(x.size(), 40u);
  EXPECT_NEAR(x[7], 0.087, 1e-12);
}

TEST(TargetFile, ErrorsNameTheMissingColumnAndTheBadLine) {
  try {
    read_target(write("t_missing.csv", table()), "x_b", 0.0025, 600.0);
    FAIL();
  } catch (const RunFileError& e) {
    EXPECT_NE(std::string(e.what()).find("x_b"), std::string::npos) << e.what();
  }
  try {
    read_target(write("t_bad.csv", table("12")), "x_w", 0.0025, 600.0);
    FAIL();
  } catch (const RunFileError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("line 15"), std::string::npos) << m;  // metadata, header, then row 12
    EXPECT_NE(m.find("x_w"), std::string::npos) << m;
  }
}

TEST(TargetFile, ChannelByNumberAndTheLengthLimit) {
  const std::string p = write("t_number.csv", table());
  const Target t = read_target(p, "2", 0.0025, 600.0);  // t, notes, x_w: the second column after t
  EXPECT_EQ(t.channel, "x_w");
  EXPECT_NEAR(t.values[7], 0.087, 1e-12);
  try {
    read_target(p, "9", 0.0025, 600.0);
    FAIL();
  } catch (const RunFileError& e) {
    EXPECT_NE(std::string(e.what()).find("no column number 9"), std::string::npos) << e.what();
  }
  try {
    read_target(p, "x_w", 0.0025, 0.05);  // 40 samples are 0.1 s
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--max-length"), std::string::npos) << e.what();
  }
}

TEST(TargetFile, ReadsRpcTimeHistories) {
  Rpc3File f;
  f.period_s = 0.0025;
  f.channels = {{"x_w", "m", std::vector<double>(3000, 0.0)}};
  for (std::size_t i = 0; i < 3000; ++i) f.channels[0].values[i] = 0.08 + 0.01 * std::sin(0.01 * static_cast<double>(i));
  const std::string p = temp_path("target.tim");
  write_rpc3_file(f, p, Rpc3DataType::kFloatingPoint);
  const auto x = read_target(p, "x_w", 0.0025, 600.0).values;
  ASSERT_GE(x.size(), 3000u);
  EXPECT_NEAR(x[1234], f.channels[0].values[1234], 1e-7);
}

TEST(RoadTarget, WheelFollowsTheRoadAndScalesWithTheClass) {
  const RigConfig c = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
  RoadTargetSpec s;
  s.speed_m_s = 2.0;
  s.duration_s = 20.0;
  const RoadTarget road_c = make_road_target(c.quarter_car, s);
  s.road_class = IsoRoadClass::kD;
  const RoadTarget road_d = make_road_target(c.quarter_car, s);
  ASSERT_EQ(road_c.wheel.size(), 8000u);
  auto rms = [&](const std::vector<double>& x) {
    double e = 0;
    for (double v : x) e += (v - s.offset) * (v - s.offset);
    return std::sqrt(e / static_cast<double>(x.size()));
  };
  // Class D has four times the PSD of C: twice the RMS, same phases (seed).
  EXPECT_NEAR(rms(road_d.wheel) / rms(road_c.wheel), 2.0, 1e-6);
  EXPECT_GT(rms(road_c.wheel), 1e-3);
  // Below the wheel hop the wheel follows the road through its stiff tyre.
  double diff = 0;
  for (std::size_t i = 0; i < road_c.wheel.size(); ++i) diff += std::pow(road_c.wheel[i] - road_c.road[i], 2);
  EXPECT_LT(std::sqrt(diff / static_cast<double>(road_c.wheel.size())), 0.2 * rms(road_c.wheel));
  // Faded in and out: the rig starts and ends at rest at the offset.
  EXPECT_DOUBLE_EQ(road_c.wheel.front(), s.offset);
  EXPECT_NEAR(road_c.wheel.back(), s.offset, 1e-6);
}

}  // namespace
}  // namespace rigctl
