// The console's Foxglove server under hostile and careless clients
// (tests/node/hostile_clients.cjs) against real `rigctl run` processes on
// loopback: a watching console's signed stop stops the rig and a silent
// holder loses control; floods, an oversized message, a frame that never
// ends, a cross-origin upgrade and connections past the limit are refused
// or closed while a well-behaved client gets every sample and the run log
// is complete; memory returns after rounds of connect-flood-disconnect; a
// command replayed into a restarted process is refused. Every wait is for
// an event (a line, an answer, a status, a close), never a fixed time.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "background_process.hpp"
#include "config_edit.hpp"
#include "foxglove_checks.hpp"
#include "log_messages.hpp"
#include "node_client.hpp"
#include "operator_commands.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "rt/wall_clock.hpp"
#include "state_changes.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rigctl::test;

const std::string kRigctl = RIGCTL_BINARY;
constexpr double kStartTimeoutS = 120.0;  // a deadline for what never happens

std::string key_bytes() { return std::string(32, '\x07'); }

int count_lines(const std::string& text, const std::string& fragment) {
  int n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) n += line.find(fragment) != std::string::npos ? 1 : 0;
  return n;
}

// Open file descriptors of a process.
std::size_t open_fds(pid_t pid) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd")) ++n;
  return n;
}

// Once the server has closed every connection of a round: as many
// descriptors open as before it (a deadline only for what never happens).
bool wait_for_fds(pid_t pid, std::size_t baseline) {
  for (int i = 0; i < 6000; ++i) {
    if (open_fds(pid) <= baseline) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// VmRSS of a process [kB].
long rss_kb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

class HostileClients : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_hostile_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    std::ofstream(path("rig.key")) << key_bytes();
    fs::permissions(path("rig.key"), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // The shipped quarter car, paced, its overrun detector only indicating,
  // its steps held long, with `websocket` as the telemetry's server.
  void write_config(const std::string& websocket, double staleness_s = 2.0) {
    std::string text = edit(without_overrun_stop(shipped_config()), "step_hold_s: 4\\.0", "step_hold_s: 60.0");
    text = edit(text, "(  log_dir: runs[^\n]*\n)", "$1  websocket: " + websocket + "\n");
    text = edit(text, "key_file: operator\\.key", "key_file: rig.key");
    std::ofstream(path("quarter_car.yaml")) << edit(text, "staleness_s: 2\\.0", "staleness_s: " + std::to_string(staleness_s));
  }

  std::unique_ptr<BackgroundProcess> start_rig(int port, const std::vector<std::string>& extra, const std::string& name = "run") {
    std::vector<std::string> argv = {kRigctl, "run", path("quarter_car.yaml"), "--lcm-url", "memq://",
                                     "--ws", "127.0.0.1:" + std::to_string(port), "--no-realtime", "--log", path(name + ".lcm")};
    argv.insert(argv.end(), extra.begin(), extra.end());
    auto rig = std::make_unique<BackgroundProcess>(argv, path(name + ".out"));
    EXPECT_TRUE(rig->wait_for("foxglove: ws://127.0.0.1:" + std::to_string(port), kStartTimeoutS)) << rig->output();
    return rig;
  }

  nlohmann::json run_node(const std::string& scenario, int port, std::vector<std::string> args) {
    const std::string out = path(scenario + ".json");
    args.insert(args.end(), {"--scenario", scenario, "--url", "ws://127.0.0.1:" + std::to_string(port), "--out", out});
    const auto r = run_command(node_command("hostile_clients.cjs", args));
    const auto result = read_json(out);
    EXPECT_EQ(r.exit_code, 0) << r.output << "\n" << result.dump(2);
    return result;
  }

  fs::path dir_;
};

TEST_F(HostileClients, AWatchingConsolesStopStopsTheRigAndASilentHolderLosesControl) {
  // control_timeout_s 2: a holder that answers no ping for 2 s loses
  // control; the well-behaved consoles answer within milliseconds.
  write_config("{port: 8765, control_timeout_s: 2.0}");
  const int port = free_tcp_port();
  auto rig = start_rig(port, {"--operator", "--key", path("rig.key")});
  const std::string key = key_bytes();
  const auto r = run_node("control", port, {"--key", hex(reinterpret_cast<const uint8_t*>(key.data()), key.size())});
  ASSERT_EQ(rig->stop(), 0) << rig->output();
  ASSERT_FALSE(r.contains("error")) << r.dump(2);

  EXPECT_EQ(r["takeControl"]["reason"], "accepted") << r;
  EXPECT_EQ(r["start"]["reason"], "accepted") << r;
  ASSERT_FALSE(r["controlStatus"].empty());
  EXPECT_TRUE(std::regex_search(r["controlStatus"].back().get<std::string>(),
                                std::regex(R"(^control held by alice since \d\d:\d\d:\d\d UTC$)")))
      << r["controlStatus"];
  EXPECT_EQ(r["bStart"]["reason"], "not_in_control") << r["bStart"];
  EXPECT_EQ(r["bStop"]["reason"], "accepted") << r["bStop"];  // whoever holds control
  EXPECT_EQ(r["cTakeControl"]["reason"], "accepted") << r["cTakeControl"];
  EXPECT_EQ(r["bTakeControl"]["reason"], "accepted") << r["bTakeControl"];  // once carol fell silent
  EXPECT_EQ(r["cStartAfter"]["reason"], "not_in_control") << r["cStartAfter"];

  const std::string events = read_file(path("run.lcm.events"));
  EXPECT_EQ(count_lines(events, "message=\"stop accepted\""), 1) << events;  // the state machine took bob's stop
  const auto changes = state_changes(events);
  EXPECT_NE(std::find(changes.begin(), changes.end(), "running -> stopping"), changes.end()) << events;
  EXPECT_EQ(count_lines(events, "console control of 'carol' released: it answered no ping for"), 1) << events;
  EXPECT_EQ(count_lines(events, "console control taken by 'bob'"), 1) << events;
  EXPECT_EQ(count_lines(events, "operator command rejected (not_in_control)"), 2) << events;
  EXPECT_NE(rig->output().find("not_in_control 2"), std::string::npos) << rig->output();  // the receiver's counters
}

TEST_F(HostileClients, FloodsOversizedFramesAndTheLimitAreRefusedWhileAGoodClientGetsEverySample) {
  // Four clients at most: the good one and three more; a client silent for
  // 4 s is closed (the frame sent a byte a second).
  write_config("{port: 8765, client_queue: 12000, max_clients: 4, client_timeout_s: 4.0}");
  const int port = free_tcp_port();
  const int samples = 400 * 14;
  auto good = std::make_unique<BackgroundProcess>(
      node_argv("foxglove_client.cjs", {"--url", "ws://127.0.0.1:" + std::to_string(port), "--subprotocol",
                                        "foxglove.websocket.v1", "--topic", "RIGCTL_SAMPLE", "--count", std::to_string(samples),
                                        "--out", path("good.json")}),
      path("good.out"));
  ASSERT_TRUE(good->wait_for("started", kStartTimeoutS)) << good->output();
  auto rig = start_rig(port, {"--duration", "15"});
  ASSERT_TRUE(good->wait_for("subscribed", kStartTimeoutS)) << good->output();
  const auto r = run_node("limits", port, {"--max-clients", "4"});
  ASSERT_EQ(good->wait(), 0) << good->output();
  ASSERT_EQ(rig->wait(), 0) << rig->output();
  ASSERT_FALSE(r.contains("error")) << r.dump(2);

  EXPECT_EQ(r["crossOrigin"], 403);
  EXPECT_EQ(r["sameOrigin"], 101);   // the server's own page
  EXPECT_EQ(r["reboundHost"], 403);  // another name for 127.0.0.1
  // 1009 when the server's close frame reaches the client; 1006 when the
  // server's close of a socket still holding the client's unread megabyte
  // resets the connection first (a race of the two machines' TCP stacks, seen
  // under load). The server's own count below is what says it refused it.
  EXPECT_TRUE(r["oversized"]["code"] == 1009 || r["oversized"]["code"] == 1006) << r["oversized"];
  EXPECT_GT(r["flood"]["sent"].get<int>(), 0);
  // Closed by the server (a close seen within the script's deadline; the
  // report's queue_overflow below says why). Not judged by how many requests
  // the client had queued by then: on a busy machine the client queues all
  // of them before the server has read enough to overflow.
  EXPECT_TRUE(r["flood"].contains("code")) << r["flood"];
  EXPECT_TRUE(r["slowFrame"]["upgraded"].get<bool>()) << r["slowFrame"];
  EXPECT_LT(r["slowFrame"]["bytesSent"].get<int>(), 100) << r["slowFrame"];  // closed before the frame was complete
  EXPECT_EQ(r["pastTheLimit"], 503);
  EXPECT_EQ(r["afterClosing"], 101);

  // The well-behaved client got every sample, in order, as in the log.
  const auto g = read_json(path("good.json"));
  EXPECT_EQ(g["received"], samples);
  EXPECT_EQ(g["gaps"], 0);
  EXPECT_EQ(g["outOfOrder"], 0);
  EXPECT_EQ(expect_samples_match_log(g["messages"], samples_by_tick(path("run.lcm"))), samples);
  // The run log is complete: every tick of the 15 s, none missing.
  const auto log = samples_by_tick(path("run.lcm"));
  ASSERT_GE(log.size(), 400u * 15u);
  EXPECT_EQ(static_cast<std::size_t>(log.rbegin()->first - log.begin()->first + 1), log.size());
  EXPECT_EQ(rig->output().find("records dropped"), std::string::npos) << rig->output();
  // Each refusal counted in the report and written to the event log.
  const std::string out = rig->output();
  for (const char* kind : {"origin 2", "message_too_big 1", "queue_overflow 1", "unresponsive 1", "too_many_clients 1"}) {
    EXPECT_NE(out.find(kind), std::string::npos) << kind << "\n" << out;
  }
  const std::string events = read_file(path("run.lcm.events"));
  for (const char* kind : {"origin: upgrade", "message_too_big: client", "queue_overflow: client", "unresponsive: client",
                           "too_many_clients: upgrade"}) {
    EXPECT_GE(count_lines(events, kind), 1) << kind << "\n" << events;
  }
}

TEST_F(HostileClients, MemoryReturnsAfterRoundsOfConnectFloodDisconnect) {
  write_config("{port: 8765}");
  const int port = free_tcp_port();
  auto rig = start_rig(port, {"--duration", "600"});
  const std::size_t fds = open_fds(rig->pid());
  // One round first: the server thread's allocator arena and the
  // connection objects' pools are made once, not per client.
  run_node("flood-round", port, {"--clients", "15"});
  ASSERT_TRUE(wait_for_fds(rig->pid(), fds));
  const long start = rss_kb(rig->pid());
  std::vector<long> after;
  for (int round = 0; round < 10; ++round) {
    const auto r = run_node("flood-round", port, {"--clients", "15"});
    ASSERT_FALSE(r.contains("error")) << r.dump(2);
    ASSERT_TRUE(wait_for_fds(rig->pid(), fds)) << "round " << round << ": connections still open";
    after.push_back(rss_kb(rig->pid()));
  }
  rig->stop();
  std::string seen;
  for (long a : after) seen += " " + std::to_string(a / 1024) + " MB";
  std::cout << "RSS after the first round " << start / 1024 << " MB, after each of 10 more:" << seen << "\n";
  // Within a few MB: each round's clients queued up to 15 x 2 MiB.
  EXPECT_LT(after.back() - start, 4 * 1024) << "RSS " << start << " kB, then" << seen;
}

TEST_F(HostileClients, ACommandReplayedIntoARestartedProcessIsRefused) {
  // A staleness window of 60 s, so that only the restart can refuse the replay.
  write_config("{port: 8765}", 60.0);
  const int port = free_tcp_port();
  {
    auto first = start_rig(port, {"--operator"}, "first");
    // Signed once the first process runs; captured on their way to it.
    const auto key = rigctl::OperatorKey::from_bytes(key_bytes().data(), 32);
    auto claim = command("take_control", 1, 0.0, rigctl::wall_utime_now(), "mallory");
    auto reset = command("reset", 2, 0.0, rigctl::wall_utime_now(), "mallory");
    std::ofstream payloads(path("captured.jsonl"));
    for (auto* m : {&claim, &reset}) {
      rigctl::sign(*m, key);
      payloads << nlohmann::json{{"id", m->sequence}, {"sender", m->sender}, {"sequence", m->sequence}, {"utime", m->utime},
                                 {"command", m->command}, {"value", 0.0}, {"tag", hex(m->tag, 32)}}
                      .dump()
               << "\n";
    }
    payloads.close();
    const auto r = run_node("send", port, {"--payloads", path("captured.jsonl")});
    EXPECT_EQ(r["answers"][0]["reason"], "accepted") << r;
    EXPECT_EQ(r["answers"][1]["reason"], "accepted") << r;
    ::kill(first->pid(), SIGKILL);  // no orderly end: a crash, a power cut
    first->wait();
  }
  auto second = start_rig(port, {"--operator"}, "second");
  const auto r = run_node("send", port, {"--payloads", path("captured.jsonl")});
  ASSERT_EQ(second->stop(), 0) << second->output();
  for (const auto& a : r["answers"]) {
    EXPECT_EQ(a["reason"], "stale") << a;
    EXPECT_NE(a["message"].get<std::string>().find("before this rig's command receiver started"), std::string::npos) << a;
  }
  EXPECT_EQ(count_lines(read_file(path("second.lcm.events")), "before this rig's command receiver started"), 2);
}

}  // namespace
