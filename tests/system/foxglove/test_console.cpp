// The operator console (docs/console.md) in a real browser: Debian's
// chromium, headless, driven by puppeteer-core (tests/node/console_browser.cjs)
// against a paced simulated quarter-car run in operator mode. The browser
// signs with WebCrypto; the rig's command receiver verifies. What the page
// showed is checked here against what the run wrote in its event log.
// Screenshots go to BUILD_DIR/console_screenshots (docs/console/ holds the
// committed ones).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "background_process.hpp"
#include "rigctl/procedure_t.hpp"
#include "config_edit.hpp"
#include "node_client.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "state_changes.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rigctl::test;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kScreenshots = std::string(RIGCTL_BUILD_DIR) + "/console_screenshots";
constexpr double kStartTimeoutS = 120.0;  // a deadline for what never happens

// 32 key bytes and their hex, as the operator types them (xxd -p rig.key).
std::string key_bytes(char first) {
  std::string k;
  for (int i = 0; i < 32; ++i) k.push_back(static_cast<char>(first + i));
  return k;
}
std::string hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (unsigned char c : bytes) out += {digits[c >> 4], digits[c & 15]};
  return out;
}


int count_lines(const std::string& text, const std::string& fragment) {
  int n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) n += line.find(fragment) != std::string::npos ? 1 : 0;
  return n;
}

class Console : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_console_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // Paced on a loaded machine: an overrun burst indicates rather than stops;
    // steps held 60 s, so the profile (which ends in a hold of its own in
    // operator mode) outlasts the test however slowly the browser goes.
    std::ofstream(path("quarter_car.yaml"))
        << edit(without_overrun_stop(shipped_config()), "step_hold_s: 4\\.0", "step_hold_s: 60.0");
    std::ofstream(path("rig.key")) << key_bytes(1);
    fs::permissions(path("rig.key"), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // A paced operator-mode run serving the console; returns it once it listens.
  std::unique_ptr<BackgroundProcess> start_rig(int port, const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {kRigctl, "run", path("quarter_car.yaml"), "--operator", "--key", path("rig.key"),
                                     "--lcm-url", "memq://", "--ws", "127.0.0.1:" + std::to_string(port),
                                     "--no-realtime", "--log", path("run.lcm")};
    argv.insert(argv.end(), extra.begin(), extra.end());
    auto rig = std::make_unique<BackgroundProcess>(argv, path("run.out"));
    EXPECT_TRUE(rig->wait_for("foxglove: ws://127.0.0.1:" + std::to_string(port), kStartTimeoutS)) << rig->output();
    return rig;
  }

  nlohmann::json run_browser(int port, const std::string& scenario) {
    const auto r = run_command(node_command(
        "console_browser.cjs", {"--url", "http://127.0.0.1:" + std::to_string(port) + "/", "--key", hex(key_bytes(1)),
                                "--wrong-key", hex(key_bytes(2)), "--screenshots", kScreenshots, "--scenario", scenario,
                                "--out", path("browser.json")}));
    const auto result = read_json(path("browser.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output << "\n" << result.dump(2);
    return result;
  }

  fs::path dir_;
};

TEST_F(Console, SignedCommandsFromTheBrowserDriveTheRigAndForgeriesChangeNothing) {
  const int port = free_tcp_port();
  auto rig = start_rig(port, {});
  const auto r = run_browser(port, "commands");
  ASSERT_EQ(rig->stop(), 0) << rig->output();
  ASSERT_FALSE(r.contains("error")) << r.dump(2);

  // WebCrypto in chromium signs the canonical bytes as the rig does (the
  // test vector of docs/operator-commands.md).
  const std::string canonical = r["testVector"]["canonical"];
  EXPECT_EQ(canonical.size(), 2u * 82);
  EXPECT_EQ(canonical.substr(0, 8), "72696763");
  EXPECT_EQ(canonical.substr(canonical.size() - 16), "3f847ae147ae147b");
  EXPECT_EQ(r["testVector"]["tag"], "5346b1f0a62ff91f2d21aba62f9e9eed9d13b6ba6a939b321319de2fc82773fd");
  EXPECT_GT(r["samplesSeen"].get<int>(), 600);  // the traces updated
  EXPECT_GT(r["framesDrawn"].get<int>(), 0);
  // Paused, the plot stands still while every sample is still recorded.
  EXPECT_EQ(r["paused"]["endBefore"], r["paused"]["endAfter"]) << r["paused"];
  EXPECT_GT(r["paused"]["samplesAfter"].get<int>(), r["paused"]["samplesBefore"].get<int>() + 100) << r["paused"];
  EXPECT_EQ(r["paused"]["windowS"], 60);
  EXPECT_EQ(r["takeControl"]["reason"], "accepted") << r["takeControl"];
  for (const auto& a : r["answers"]) EXPECT_EQ(a["reason"], "accepted") << a;
  // Refused with their reasons, and the rig stayed running.
  EXPECT_EQ(r["wrongKey"]["reason"], "bad_tag") << r["wrongKey"];
  EXPECT_EQ(r["stateAfterWrongKey"], "running");
  EXPECT_EQ(r["stale"]["reason"], "stale") << r["stale"];
  EXPECT_EQ(r["stateAfterStale"], "running");
  EXPECT_EQ(r["hold"]["reason"], "accepted") << r["hold"];
  EXPECT_EQ(r["replayed"]["reason"], "replayed") << r["replayed"];
  EXPECT_EQ(r["stateAfterHold"], "holding");
  EXPECT_EQ(r["setpoint"]["reason"], "accepted") << r["setpoint"];
  EXPECT_EQ(r["setpointOutOfRange"]["reason"], "out_of_limits") << r["setpointOutOfRange"];
  // The second console watches: it may hold (stop and hold from every
  // station), but neither resume nor take control.
  EXPECT_EQ(r["secondHold"]["reason"], "accepted") << r["secondHold"];
  EXPECT_EQ(r["secondResume"]["reason"], "not_in_control") << r["secondResume"];
  EXPECT_EQ(r["secondTakeControl"]["reason"], "control_held") << r["secondTakeControl"];
  EXPECT_EQ(r["stateAfterSecond"], "holding");
  // Malformed messages are answered, and the console goes on working.
  const auto& bad = r["malformed"];
  ASSERT_EQ(bad["answers"].size(), 3u) << bad;
  for (const auto& a : bad["answers"]) EXPECT_EQ(a["reason"], "malformed") << a;
  std::set<std::string> statuses(bad["statuses"].begin(), bad["statuses"].end());
  for (const char* id : {"bad_request", "bad_client_message", "refused_advertise"}) EXPECT_EQ(statuses.count(id), 1u) << bad;
  EXPECT_EQ(r["stateAfterMalformed"], "holding");
  // A console that dropped its connection right after a command freed control.
  EXPECT_EQ(r["secondTakeControlAfterRelease"]["reason"], "accepted");
  EXPECT_EQ(r["takeControlAgain"]["reason"], "accepted") << r["takeControlAgain"];
  EXPECT_EQ(r["stop"]["reason"], "accepted");
  EXPECT_EQ(r["finalState"], "hydraulics_high");

  // The run's event log: the states in order, one hold, the refusals with their reasons.
  const std::string events = read_file(path("run.lcm.events"));
  auto changes = state_changes(events);
  const std::vector<std::string> expected = {"faulted -> off", "off -> hydraulics_low", "hydraulics_low -> hydraulics_high",
                                             "hydraulics_high -> armed", "armed -> running", "running -> holding"};
  ASSERT_GE(changes.size(), expected.size()) << events;
  EXPECT_EQ(std::vector<std::string>(changes.begin(), changes.begin() + 6), expected) << events;
  EXPECT_EQ(changes.back(), "stopping -> hydraulics_high") << events;
  EXPECT_EQ(count_lines(events, "message=\"hold accepted\""), 1) << events;
  EXPECT_EQ(count_lines(events, "message=\"setpoint 0.02 accepted\""), 1) << events;
  for (const char* reason : {"(bad_tag)", "(stale)", "(replayed)"}) {
    EXPECT_EQ(count_lines(events, "operator command rejected " + std::string(reason)), 1) << reason << "\n" << events;
  }
}

TEST_F(Console, ALimitTripShowsItsDetectorAndTheRefusedReset) {
  const int port = free_tcp_port();
  auto rig = start_rig(port, {"--fault", "rail@0.5:x_r"});  // the LVDT at its rail: open circuit
  const auto r = run_browser(port, "trip");
  ASSERT_EQ(rig->stop(), 3) << rig->output();  // ended faulted: the run's fault exit
  ASSERT_FALSE(r.contains("error")) << r.dump(2);
  EXPECT_EQ(r["state"], "faulted");
  // The first trip of the tick is the one telemetry carries: x_r beyond its limits.
  // (On a loaded machine the overrun detectors, which only indicate, may trip too.)
  EXPECT_NE(r["tripped"].dump().find("\"limits.x_r\""), std::string::npos) << r["tripped"];
  EXPECT_NE(r["trips"].dump().find("limit_tripped: x_r = 0.2 m outside its limits (action interlock)"), std::string::npos)
      << r["trips"];
  EXPECT_EQ(r["reset"]["reason"], "accepted");  // authentic: queued; the rig refuses it
  EXPECT_NE(r["events"].dump().find("reset refused: a fault is still present"), std::string::npos) << r["events"];
  const std::string events = read_file(path("run.lcm.events"));
  EXPECT_GE(count_lines(events, "reset refused: a fault is still present"), 1) << events;
  EXPECT_EQ(state_changes(events).size(), 0u) << events;  // never left faulted
}

// A block program of 4-cycle passes (two rows of two 2 Hz cycles: 2 s a
// pass), long enough to outlast the browser: the console's hold, resume and
// "stop at the end of the block" on a running procedure.
TEST_F(Console, AProcedureIsShownAndHeldResumedAndStoppedAtItsBlockEnd) {
  std::ofstream(path("proc.yaml")) << "ramp_rate: 0.02\n"
                                      "steps:\n"
                                      "  - blocks:\n"
                                      "      repeats: 100000\n"
                                      "      rows:\n"
                                      "        - {mean: 0.08, amplitude: 0.004, frequency: 2.0, cycles: 2}\n"
                                      "        - {mean: 0.085, amplitude: 0.006, frequency: 2.0, cycles: 2}\n";
  const int port = free_tcp_port();
  auto rig = start_rig(port, {"--procedure", path("proc.yaml")});
  const auto r = run_browser(port, "procedure");
  // Hydraulics off after the stop ends the run by itself (the deadline is for a run that does not).
  rig->wait_until([](const std::string&) { return false; }, kStartTimeoutS);
  ASSERT_EQ(rig->stop(), 0) << rig->output();
  ASSERT_FALSE(r.contains("error")) << r.dump(2);
  for (const char* answer : {"takeControl", "hold", "resume", "stopAtBlockEnd", "hydraulicsOff"}) {
    EXPECT_EQ(r[answer]["reason"], "accepted") << answer << ": " << r[answer];
  }
  // The page showed the request until the block ended, then not.
  EXPECT_TRUE(r["sawStopRequest"].get<bool>()) << r.dump(2);
  EXPECT_EQ(r["requestAfterStop"], "false");
  EXPECT_GT(r["cyclesAtStop"].get<int>(), r["cyclesAtHold"].get<int>());

  // The event log: the commands, the block end and the stop after it.
  const std::string events = read_file(path("run.lcm.events"));
  for (const char* line : {"message=\"hold accepted\"", "message=\"resume accepted\"",
                           "message=\"stop_at_block_end accepted\"", "code=block_end_stop"}) {
    EXPECT_EQ(count_lines(events, line), 1) << line << "\n" << events;
  }
  const auto changes = state_changes(events);
  const std::vector<std::string> tail = {"armed -> running", "running -> holding", "holding -> running",
                                         "running -> stopping", "stopping -> hydraulics_high", "hydraulics_high -> off"};
  ASSERT_GE(changes.size(), tail.size()) << events;
  EXPECT_EQ(std::vector<std::string>(changes.end() - static_cast<std::ptrdiff_t>(tail.size()), changes.end()), tail) << events;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(events, m, std::regex(R"(tick=(\d+) state=running code=block_end_stop value=(\d+))"))) << events;
  const long stop_tick = std::stol(m[1]);
  const long stopped_at = std::stol(m[2]);
  EXPECT_EQ(stopped_at % 4, 0) << "the stop came mid-pass: " << stopped_at;
  ASSERT_TRUE(std::regex_search(events, m, std::regex(R"(tick=(\d+) state=holding code=state_changed[^\n]*running -> holding)")))
      << events;
  const long hold_tick = std::stol(m[1]);
  ASSERT_TRUE(std::regex_search(events, m, std::regex(R"(tick=(\d+) state=running code=state_changed[^\n]*holding -> running)")))
      << events;
  const long resume_tick = std::stol(m[1]);

  // RIGCTL_PROCEDURE in the run log: no cycle counted while held, the
  // request on from its command to the block end, nothing counted after.
  lcm::LogFile log(path("run.lcm"), "r");
  ASSERT_TRUE(log.good());
  int64_t held_cycles = -1, last_total = -1, messages = 0, requested = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "RIGCTL_PROCEDURE") continue;
    rigctl::procedure_t p;
    ASSERT_GE(p.decode(e->data, 0, e->datalen), 0);
    ++messages;
    EXPECT_EQ(p.step_kind, "blocks");
    EXPECT_EQ(p.programmed_cycles, 400000);
    if (p.tick > hold_tick + 100 && p.tick < resume_tick) {  // the hold's ramp has ended its half-cycle
      if (held_cycles < 0) held_cycles = p.total_cycles;
      EXPECT_EQ(p.total_cycles, held_cycles) << "counted while held, tick " << p.tick;
    }
    if (p.stop_at_block_end) {
      ++requested;
      EXPECT_LE(p.tick, stop_tick);
    }
    last_total = p.total_cycles;
  }
  EXPECT_GT(messages, 50);
  EXPECT_GT(requested, 0);
  EXPECT_EQ(last_total, stopped_at);
}

}  // namespace
