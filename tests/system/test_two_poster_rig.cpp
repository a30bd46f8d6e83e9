// The two-poster end to end through its shipped config
// (config/half_car_two_poster.yaml, issue 31 item 2): `rigctl run` closes
// both posts in one tick and its run file carries both channels in order,
// each following its own demand; a limit on the rear post ends the run with
// the whole rig made safe; the `channels:` section's errors name the field.
// The run file is read here with a reader of the test's own.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "config_edit.hpp"
#include "process.hpp"
#include "read_file.hpp"

using namespace rigctl;
using rigctl::test::run_command;
namespace fs = std::filesystem;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfigName = "half_car_two_poster.yaml";

class TwoPosterRig : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_two_poster_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

struct RunFile {
  std::vector<std::string> header;
  std::map<std::string, std::vector<double>> column;
};

RunFile read_run_file(const std::string& p) {
  RunFile f;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::vector<std::string> cells;
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (f.header.empty()) {
      f.header = cells;
      continue;
    }
    for (std::size_t i = 0; i < cells.size() && i < f.header.size(); ++i) f.column[f.header[i]].push_back(std::stod(cells[i]));
  }
  return f;
}

// RMS of a - b over rows [from, to).
double rms_difference(const std::vector<double>& a, const std::vector<double>& b, std::size_t from, std::size_t to) {
  double s = 0.0;
  for (std::size_t i = from; i < to; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s / static_cast<double>(to - from));
}

}  // namespace

TEST_F(TwoPosterRig, ARunWritesBothChannelsInOrderEachFollowingItsOwnDemand) {
  const auto r = run_command(kRigctl + " run " + std::string(RIGCTL_SOURCE_DIR) + "/config/" + kConfigName +
                             " --fast --no-realtime --duration 5 --log " + path("run.lcm") + " --csv " + path("run.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const RunFile f = read_run_file(path("run.csv"));
  const std::vector<std::string> first{"t", "x_ref_1", "x_ref_2", "u_1", "u_2", "z_r1", "z_r2"};
  ASSERT_GE(f.header.size(), first.size());
  EXPECT_TRUE(std::equal(first.begin(), first.end(), f.header.begin())) << "the channels' columns in channel order";
  const auto& t = f.column.at("t");
  ASSERT_GE(t.size(), 2000u);  // 5 s at 2.5 ms
  // From 3 s on: the front steps while the rear plays its sine.
  const auto from = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), 3.0) - t.begin());
  const std::size_t to = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), 5.0) - t.begin());
  const auto& ref1 = f.column.at("x_ref_1");
  const auto& ref2 = f.column.at("x_ref_2");
  const auto& z1 = f.column.at("z_r1");
  const auto& z2 = f.column.at("z_r2");
  const auto [lo2, hi2] = std::minmax_element(ref2.begin() + static_cast<long>(from), ref2.begin() + static_cast<long>(to));
  EXPECT_NEAR(*hi2 - *lo2, 0.04, 0.002) << "the rear demand is the 20 mm sine";
  EXPECT_NEAR(ref1[from + 400], 0.11, 0.002) << "the front demand is its +30 mm step";
  // Each post follows its own demand (not the other's): the PI loops' lag
  // leaves millimetres, the other post's demand is centimetres away.
  const double own1 = rms_difference(z1, ref1, from, to), own2 = rms_difference(z2, ref2, from, to);
  EXPECT_LT(own1, 0.003);
  EXPECT_LT(own2, 0.006);
  EXPECT_GT(rms_difference(z1, ref2, from, to), 3.0 * own1);
  EXPECT_GT(rms_difference(z2, ref1, from, to), 3.0 * own2);
  // Both valves are driven, differently.
  EXPECT_GT(rms_difference(f.column.at("u_1"), f.column.at("u_2"), from, to), 0.05);
}

TEST_F(TwoPosterRig, ALimitOnTheRearPostEndsTheRunWithTheRigSafe) {
  // The rear's sine peaks at 100 mm: a 95 mm limit trips on its first crest.
  const std::string yaml = test::edit(test::shipped_config(kConfigName), "z_r2: \\[-0.012, 0.172\\]", "z_r2: [-0.012, 0.095]");
  std::ofstream(path("limited.yaml")) << yaml;
  const auto r = run_command(kRigctl + " run " + path("limited.yaml") + " --fast --no-realtime --duration 5 --log " +
                             path("run.lcm") + " --csv " + path("run.csv"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("faulted"), std::string::npos) << r.output;
  const std::string events = test::read_file(path("run.lcm.events"));
  EXPECT_NE(events.find("code=limit_tripped channel=z_r2"), std::string::npos) << events;
  // The run ended on the trip, before the rear's sine could go on: the
  // last row is at the crest, long before the 5 s.
  const RunFile f = read_run_file(path("run.csv"));
  ASSERT_FALSE(f.column.at("t").empty());
  EXPECT_LT(f.column.at("t").back(), 4.0);
  EXPECT_GT(f.column.at("z_r2").back(), 0.09);
}

TEST_F(TwoPosterRig, ChannelErrorsNameTheField) {
  const std::string yaml = test::shipped_config(kConfigName);
  // A channel's unknown feedback names the channel and the key.
  test::expect_config_error(test::edit(yaml, "feedback: z_r2", "feedback: z_r3"),
                            {"channels[1]", "controller.feedback", "z_r3"});
  // channels: beside controller: is refused with the line of controller:.
  const std::string both = test::edit(yaml, "\nchannels:", "\ncontroller: {type: pi}\nchannels:");
  test::expect_config_error(both, {"controller", "either `channels:`"});
  // The quarter car's own controllers only on the two-poster: pi and pvp.
  test::expect_config_error(test::edit(yaml, "type: pi, feedback: z_r2", "type: lqr, feedback: z_r2"),
                            {"channels[1].controller.type", "two_poster runs: pi, pvp"});
}
