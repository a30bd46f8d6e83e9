// `rigctl bridge`: a monitoring PC's Foxglove server fed from the rig
// network. A run's log is replayed by lcm-logplayer over the real udpm://
// provider, the bridge serves it, and a real Foxglove client gets the
// samples in order, valid against their schema and equal to the log, with
// the rig's gains and limits as parameters. Everything happens inside a
// network namespace the test creates: multicast never touches the host's
// network, and the server's port cannot collide with another test's.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "background_process.hpp"
#include "foxglove_checks.hpp"
#include "node_client.hpp"
#include "process.hpp"
#include "state_message.hpp"
#include "test_netns.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rigctl::test;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";
constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr double kTimeoutS = 120.0;  // a deadline for what never happens

class Bridge : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_bridge_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(Bridge, ServesALogReplayedOnTheRigNetwork) {
  TestNetns ns("bridge");
  if (!ns.ready()) GTEST_SKIP() << ns.skip_reason();
  const std::vector<std::string> in_ns = {"/usr/bin/env", "ip", "netns", "exec", ns.name()};

  const auto run = run_command(kRigctl + " run " + kConfig + " --fast --duration 3 --log " + path("run.lcm"));
  ASSERT_EQ(run.exit_code, 0) << run.output;

  std::vector<std::string> bridge_argv = in_ns;
  bridge_argv.insert(bridge_argv.end(), {kRigctl, "bridge", "--lcm-url", kUrl, "--ws", "127.0.0.1:8765", "--config", kConfig});
  BackgroundProcess bridge(bridge_argv, path("bridge.out"));
  ASSERT_TRUE(bridge.wait_for("foxglove: ws://127.0.0.1:8765", kTimeoutS)) << bridge.output();

  BackgroundProcess client(node_argv("foxglove_client.cjs",
                                     {"--url", "ws://127.0.0.1:8765", "--subprotocol", "foxglove.sdk.v1", "--topic",
                                      "RIGCTL_SAMPLE", "--count", "400", "--subscribe-all", "--out", path("client.json")},
                                     in_ns),
                           path("client.out"));
  ASSERT_TRUE(client.wait_for("connected", kTimeoutS)) << client.output();

  const auto play = run_command(ns.exec_prefix() + "lcm-logplayer --lcm-url='" + kUrl + "' " + path("run.lcm"));
  ASSERT_EQ(play.exit_code, 0) << play.output;
  ASSERT_EQ(client.wait(), 0) << client.output();
  // The operator console's page on the same port (watch-only here: the
  // bridge offers no command channel), fetched over plain HTTP as a
  // browser would, with bash's /dev/tcp inside the namespace.
  const auto page = run_command(ns.exec_prefix() +
                                "bash -c 'exec 3<>/dev/tcp/127.0.0.1/8765 && printf \"GET / HTTP/1.1\\r\\nHost: "
                                "127.0.0.1:8765\\r\\nConnection: close\\r\\n\\r\\n\" >&3 && cat <&3'");
  EXPECT_EQ(page.exit_code, 0) << page.output;
  EXPECT_EQ(page.output.rfind("HTTP/1.1 200", 0), 0U) << page.output.substr(0, 400);
  EXPECT_NE(page.output.find("Content-Security-Policy"), std::string::npos) << page.output.substr(0, 400);
  EXPECT_NE(page.output.find("<title>rigctl console</title>"), std::string::npos) << page.output.substr(0, 400);
  EXPECT_EQ(bridge.stop(), 0) << bridge.output();
  EXPECT_NE(bridge.output().find("(foxglove.sdk.v1)"), std::string::npos) << bridge.output();

  const auto r = read_json(path("client.json"));
  EXPECT_EQ(r["subprotocol"], "foxglove.sdk.v1");
  // Watch-only: the page's commands have no channel to go to.
  const auto& capabilities = r["serverInfo"]["capabilities"];
  EXPECT_EQ(std::find(capabilities.begin(), capabilities.end(), "clientPublish"), capabilities.end()) << capabilities;
  EXPECT_EQ(r["received"], 400);
  EXPECT_EQ(r["outOfOrder"], 0);
  // UDP multicast on loopback: at 400 Hz nothing is lost on these machines;
  // 1 % allowed for a loaded one (as in test_lcm_udpm.cpp).
  EXPECT_LE(r["gaps"].get<int>(), 4);
  EXPECT_EQ(r["invalid"], 0) << r["validationErrors"];
  EXPECT_EQ(expect_samples_match_log(r["messages"], samples_by_tick(path("run.lcm"))), 400);
  std::map<std::string, double> parameters;
  for (const auto& p : r["parameters"]) parameters[p["name"]] = p["value"].get<double>();
  EXPECT_EQ(parameters["controller.kp"], 80.0);
  EXPECT_EQ(parameters["limits.x_r.min"], -0.012);
}

// The statuses over the wire: a trip that faults the rig is an error with
// an id, and a fault reset removes it. The rig's STATE messages are
// published by the test itself on the namespace's udpm, as a rig would.
TEST_F(Bridge, ATripIsAStatusUntilTheFaultIsReset) {
  TestNetns ns("bridge-status");
  if (!ns.ready()) GTEST_SKIP() << ns.skip_reason();
  const std::vector<std::string> in_ns = {"/usr/bin/env", "ip", "netns", "exec", ns.name()};
  std::vector<std::string> bridge_argv = in_ns;
  bridge_argv.insert(bridge_argv.end(), {kRigctl, "bridge", "--lcm-url", kUrl, "--ws", "127.0.0.1:8765"});
  BackgroundProcess bridge(bridge_argv, path("bridge.out"));
  ASSERT_TRUE(bridge.wait_for("foxglove: ws://127.0.0.1:8765", kTimeoutS)) << bridge.output();
  BackgroundProcess client(node_argv("foxglove_client.cjs",
                                     {"--url", "ws://127.0.0.1:8765", "--subprotocol", "foxglove.websocket.v1", "--topic",
                                      "RIGCTL_STATE", "--until-removed", "trip:", "--out", path("client.json")},
                                     in_ns),
                           path("client.out"));
  ASSERT_TRUE(client.wait_for("connected", kTimeoutS)) << client.output();

  // The rig's side, from a thread inside the namespace: running, a limit
  // trip that interlocks, the operator's reset. Sent again every 100 ms
  // until the client has seen the removal (UDP may lose a datagram).
  std::atomic<bool> done{false};
  std::string ns_error;
  std::thread rig([&] {
    ns_error = ns.enter_this_thread();
    if (!ns_error.empty()) return;
    lcm::LCM lcm(kUrl);
    const rigctl::state_t sequence[] = {
        state_message("running", "", "", 10),
        state_message("faulted", "limit_tripped", "x_r = 0.3 m outside its limits (action interlock)", 20),
        state_message("off", "fault_reset", "every fault cleared", 30),
    };
    while (!done.load()) {
      for (const auto& st : sequence) {
        lcm.publish("RIGCTL_STATE", &st);
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
  });
  const int status = client.wait();
  done.store(true);
  rig.join();
  ASSERT_TRUE(ns_error.empty()) << ns_error;
  ASSERT_EQ(status, 0) << client.output();

  const auto r = read_json(path("client.json"));
  bool error_trip = false;
  for (const auto& s : r["statuses"]) {
    if (s.value("id", "") == "trip:limit_tripped:x_r") {
      error_trip = true;
      EXPECT_EQ(s["level"], 2) << s;
      EXPECT_NE(s["message"].get<std::string>().find("x_r = 0.3 m"), std::string::npos) << s;
    }
  }
  EXPECT_TRUE(error_trip) << r["statuses"];
  EXPECT_NE(std::find(r["removedStatuses"].begin(), r["removedStatuses"].end(), "trip:limit_tripped:x_r"),
            r["removedStatuses"].end())
      << r["removedStatuses"];
  for (const auto& id : r["removedStatuses"]) EXPECT_NE(id, "rig_state") << "the rig state is replaced, never removed";
}

}  // namespace
