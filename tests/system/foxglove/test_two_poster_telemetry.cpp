// A two-poster run (config/half_car_two_poster.yaml, two control channels in
// one tick) served by `rigctl run --ws` to real clients: a Foxglove client
// (tests/node/foxglove_client.cjs) gets RIGCTL_CHANNELS with its schema,
// every message valid and equal to the run log's, and the console in
// headless chromium (tests/node/console_browser.cjs, scenario channels)
// lists and draws both posts' demands, feedbacks and valves, each demand
// with its feedback in a strip of its own.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <set>
#include <string>

#include "background_process.hpp"
#include "config_edit.hpp"
#include "node_client.hpp"
#include "process.hpp"
#include "rigctl/channels_t.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rigctl::test;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kScreenshots = std::string(RIGCTL_BUILD_DIR) + "/console_screenshots";
constexpr double kStartTimeoutS = 120.0;  // deadlines for what never happens

std::map<int64_t, rigctl::channels_t> channels_by_tick(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  std::map<int64_t, rigctl::channels_t> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "RIGCTL_CHANNELS") continue;
    rigctl::channels_t c;
    if (c.decode(e->data, 0, e->datalen) >= 0) out[c.tick] = c;
  }
  return out;
}

class TwoPosterTelemetry : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_two_poster_ws_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // Paced on a loaded machine: the overrun detector only indicates (it does already).
    std::ofstream(path("rig.yaml")) << shipped_config("half_car_two_poster.yaml");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(TwoPosterTelemetry, AFoxgloveClientGetsEveryFurtherChannelValidAndAsInTheLog) {
  const int port = free_tcp_port();
  auto client = std::make_unique<BackgroundProcess>(
      node_argv("foxglove_client.cjs", {"--url", "ws://127.0.0.1:" + std::to_string(port), "--out", path("client.json"),
                                        "--subprotocol", "foxglove.websocket.v1", "--topic", "RIGCTL_CHANNELS",
                                        "--count", "400", "--subscribe-all"}),
      path("client.out"));
  ASSERT_TRUE(client->wait_for("started", kStartTimeoutS)) << client->output();
  auto run = std::make_unique<BackgroundProcess>(
      std::vector<std::string>{kRigctl, "run", path("rig.yaml"), "--no-realtime", "--duration", "4", "--log",
                               path("run.lcm"), "--ws", "127.0.0.1:" + std::to_string(port)},
      path("run.out"));
  ASSERT_EQ(client->wait(), 0) << client->output();
  ASSERT_EQ(run->wait(), 0) << run->output();

  const auto r = read_json(path("client.json"));
  EXPECT_TRUE(r["errors"].empty()) << r["errors"];
  std::map<std::string, std::string> schemas;
  for (const auto& c : r["channels"]) schemas[c["topic"]] = c["schemaName"];
  EXPECT_EQ(schemas["RIGCTL_CHANNELS"], "rigctl.Channels");
  EXPECT_EQ(schemas["RIGCTL_SAMPLE"], "rigctl.Sample");
  const auto fields = r["schemaFields"].get<std::vector<std::string>>();
  for (const char* f : {"t", "tick", "x_ref_2", "measurement_2", "output_2", "saturated_2"}) {
    EXPECT_NE(std::find(fields.begin(), fields.end(), f), fields.end()) << f;
  }
  EXPECT_EQ(r["received"], 400);
  EXPECT_EQ(r["gaps"], 0);
  EXPECT_EQ(r["invalid"], 0) << r["validationErrors"];
  // Each message is the log's CHANNELS message of its tick.
  const auto log = channels_by_tick(path("run.lcm"));
  int compared = 0;
  for (const auto& m : r["messages"]) {
    const auto it = log.find(m["tick"].get<int64_t>());
    ASSERT_NE(it, log.end()) << m;
    EXPECT_EQ(m["t"].get<double>(), it->second.t);
    EXPECT_EQ(m["x_ref_2"].get<double>(), it->second.setpoints[0]);
    EXPECT_EQ(m["measurement_2"].get<double>(), it->second.measurements[0]);
    EXPECT_EQ(m["output_2"].get<double>(), it->second.outputs[0]);
    ++compared;
  }
  EXPECT_EQ(compared, 400);
}

TEST_F(TwoPosterTelemetry, TheConsoleListsAndDrawsBothPostsEachDemandWithItsFeedback) {
  const int port = free_tcp_port();
  // Paced, 60 s: longer than the browser needs however slowly it starts; stopped by the test.
  BackgroundProcess rig({kRigctl, "run", path("rig.yaml"), "--no-realtime", "--duration", "60", "--lcm-url", "memq://",
                         "--log", path("run.lcm"), "--ws", "127.0.0.1:" + std::to_string(port)},
                        path("run.out"));
  ASSERT_TRUE(rig.wait_for("foxglove: ws://127.0.0.1:" + std::to_string(port), kStartTimeoutS)) << rig.output();
  const auto b = run_command(node_command("console_browser.cjs", {"--url", "http://127.0.0.1:" + std::to_string(port) + "/",
                                                                  "--screenshots", kScreenshots, "--scenario", "channels",
                                                                  "--out", path("browser.json")}));
  rig.stop();
  const auto r = read_json(path("browser.json"));
  ASSERT_EQ(b.exit_code, 0) << b.output << "\n" << r.dump(2);
  ASSERT_FALSE(r.contains("error")) << r.dump(2);
  std::map<std::string, bool> checked;
  for (const auto& t : r["toggles"]) checked[t["name"]] = t["checked"];
  for (const char* name : {"x_ref_1", "z_r1", "x_ref_2", "z_r2", "u_1", "u_2", "p1_1", "p2_2"}) {
    ASSERT_EQ(checked.count(name), 1u) << name << " not listed: " << r["toggles"];
    EXPECT_TRUE(checked[name]) << name << " not drawn by default";
  }
  // The further channel's measurement and output are z_r2 and u_2 already: not listed twice.
  EXPECT_EQ(checked.count("measurement_2"), 0u);
  EXPECT_EQ(checked.count("output_2"), 0u);
  std::map<std::string, std::string> group;
  for (const auto& s : r["series"]) group[s["name"]] = s["group"];
  EXPECT_EQ(group["x_ref_1"], group["z_r1"]);
  EXPECT_EQ(group["x_ref_2"], group["z_r2"]);
  EXPECT_NE(group["x_ref_1"], group["x_ref_2"]);
  // Strips: each post's demand and feedback, the valves, the pressures.
  std::set<std::set<std::string>> strips;
  for (const auto& s : r["strips"]) strips.insert(s.get<std::set<std::string>>());
  EXPECT_EQ(strips.count({"x_ref_1", "z_r1"}), 1u) << r["strips"];
  EXPECT_EQ(strips.count({"x_ref_2", "z_r2"}), 1u) << r["strips"];
  EXPECT_EQ(strips.count({"u_1", "u_2"}), 1u) << r["strips"];
  EXPECT_GT(r["framesDrawn"].get<int>(), 0);
}

}  // namespace
