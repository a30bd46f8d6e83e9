// `rigctl run --operator` end to end (issue 7): the rig powers up faulted and
// moves only on `rigctl cmd`, over the real udpm:// provider inside a network
// namespace this test creates (never multicast on the host's interfaces).
// Every state change is in the event log in order, a forbidden command is
// refused with its reason, a forged one (wrong key) changes nothing and is
// counted, and stop then hydraulics-off ends the run (exit 0).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "background_process.hpp"
#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "state_changes.hpp"
#include "test_netns.hpp"
#include "tools/procedure/recovery_file.hpp"
#include "wait_until.hpp"

namespace fs = std::filesystem;
using rigctl::test::BackgroundProcess;
using rigctl::test::run_command;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";
const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";

using rigctl::test::read_file;

void write_key(const fs::path& p, char fill) {
  std::ofstream(p) << std::string(32, fill);
  fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
}

using rigctl::test::state_changes;

class OperatorMode : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!ns_.ready()) GTEST_SKIP() << ns_.skip_reason();
    dir_ = fs::temp_directory_path() / ("rigctl_opmode_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    key_ = (dir_ / "rig.key").string();
    wrong_key_ = (dir_ / "wrong.key").string();
    write_key(key_, 'k');
    write_key(wrong_key_, 'w');
    events_ = dir_ / "run.lcm.events";
    // The shipped config with times for a loaded machine: commands may be
    // 30 s old (not 2 s: `rigctl cmd` stamps a command before a busy
    // machine gets it to the rig; the window itself is test_operator_commands'
    // subject), and a paced loop at normal priority is late by the
    // scheduler's luck, so overruns only indicate (tests/support/config_edit.hpp).
    config_ = (dir_ / "rig.yaml").string();
    std::ofstream(config_) << rigctl::test::edit(rigctl::test::without_overrun_stop(rigctl::test::shipped_config()),
                                                 "  staleness_s: 2\\.0", "  staleness_s: 30");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  std::string in_ns(const std::string& command) const { return ns_.exec_prefix() + command; }

  // `rigctl cmd`, waiting for the rig's acknowledgement: it returns as soon
  // as one comes, so the wait is a deadline for a rig that never answers.
  // A command whose ack cannot verify waits all of it: give it a short one.
  rigctl::test::ProcessResult cmd(const std::string& command, const std::string& key,
                                  const std::string& wait_ack_s = "30") const {
    return run_command(in_ns(kRigctl + " cmd " + command + " --key " + key + " --lcm-url '" + kUrl +
                             "' --sender tester --wait-ack " + wait_ack_s + " --state-file " +
                             (dir_ / "tester.seq").string()));
  }

  // Waits until the event log contains `text` (the writer fsyncs each line
  // within a millisecond or so of the event).
  bool wait_event(const std::string& text) const {
    return rigctl::test::wait_until([&] { return read_file(events_).find(text) != std::string::npos; }, 60.0);
  }

  rigctl::test::TestNetns ns_{"opmode"};
  fs::path dir_, events_;
  std::string key_, wrong_key_, config_;
};

TEST_F(OperatorMode, CommandsDriveTheRigThroughEveryStateAndEndIt) {
  BackgroundProcess rig({"/bin/sh", "-c",
                         "exec " + in_ns(kRigctl + " run " + config_ + " --operator --key " + key_ + " --lcm-url '" +
                                         kUrl + "' --log " + (dir_ / "run.lcm").string() + " --no-realtime")},
                        (dir_ / "rig.out").string());
  ASSERT_TRUE(rig.wait_for("listening on RIGCTL_OPERATOR", 60.0)) << rig.output();
  ASSERT_TRUE(wait_event("code=run_started")) << rig.output();
  // Powered up faulted: nothing has moved.
  EXPECT_NE(read_file(events_).find("state=faulted code=run_started"), std::string::npos) << read_file(events_);

  auto step = [&](const std::string& command, const std::string& change) {
    const auto r = cmd(command, key_);
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.output;
    ASSERT_TRUE(wait_event("message=\"" + change + "\"")) << command << " did not give " << change << "\n"
                                                                << read_file(events_) << rig.output();
  };

  step("reset", "faulted -> off");
  // Forbidden: start while off. The receiver accepts it (authentic), the
  // state machine refuses it with its reason.
  {
    const auto r = cmd("start", key_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(wait_event("message=\"start refused: ")) << read_file(events_);
    const std::string ev = read_file(events_);
    const std::smatch m = [&] {
      std::smatch mm;
      std::regex_search(ev, mm, std::regex("state=off code=command_rejected .*source=operator .*message=\"start refused: ([^\"]+)\""));
      return mm;
    }();
    ASSERT_FALSE(m.empty()) << ev;
    EXPECT_FALSE(m[1].str().empty());
  }
  step("hydraulics-low", "off -> hydraulics_low");
  step("hydraulics-high", "hydraulics_low -> hydraulics_high");
  // Forged: the wrong key. `rigctl cmd` cannot verify the rig's reply (exit
  // 4), the rig logs bad_tag and stays where it was.
  {
    const std::size_t changes_before = state_changes(read_file(events_)).size();
    // No ack can verify with the wrong key, so exit 4 whatever the wait;
    // the rig's rejection is waited for in its event log below.
    const auto r = cmd("arm", wrong_key_, "1");
    EXPECT_EQ(r.exit_code, 4) << r.output;
    ASSERT_TRUE(wait_event("source=receiver")) << read_file(events_) << rig.output();
    const std::string ev = read_file(events_);
    EXPECT_NE(ev.find("code=command_rejected source=receiver"), std::string::npos) << ev;
    EXPECT_NE(ev.find("bad_tag"), std::string::npos) << ev;
    EXPECT_EQ(state_changes(ev).size(), changes_before) << ev;
  }
  step("arm", "hydraulics_high -> armed");
  step("start", "armed -> running");
  step("hold", "running -> holding");
  step("resume", "holding -> running");
  step("stop", "running -> stopping");
  ASSERT_TRUE(wait_event("message=\"stopping -> hydraulics_high\"")) << read_file(events_);
  step("hydraulics-off", "hydraulics_high -> off");

  // Stop followed by hydraulics off ends the run by itself.
  const int status = rig.wait();
  const std::string out = rig.output();
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("ended: stopped (stop_requested)"), std::string::npos) << out;
  // 10 authentic commands reached the loop (one refused there), 1 forged.
  EXPECT_NE(out.find("operator commands: 10 accepted, 1 rejected (bad_tag 1)"), std::string::npos) << out;

  const std::vector<std::string> expected{
      "faulted -> off",           "off -> hydraulics_low",   "hydraulics_low -> hydraulics_high",
      "hydraulics_high -> armed", "armed -> running",        "running -> holding",
      "holding -> running",       "running -> stopping",     "stopping -> hydraulics_high",
      "hydraulics_high -> off"};
  const std::string ev = read_file(events_);
  EXPECT_EQ(state_changes(ev), expected) << ev;
  EXPECT_NE(ev.find("# closed cleanly"), std::string::npos) << ev;
}

// A test procedure commanded by `rigctl cmd` (issue 30): hold and resume
// it, and "stop at the end of the block": a block program of 4-cycle passes
// stops at a whole pass, its recovery says so, and a resume from that
// recovery continues with the next pass.
TEST_F(OperatorMode, AProcedureIsHeldResumedAndStoppedAtItsBlockEndByRigctlCmd) {
  const std::string proc = (dir_ / "proc.yaml").string(), recovery = (dir_ / "run.recovery").string();
  std::ofstream(proc) << "ramp_rate: 0.02\n"
                         "steps:\n"
                         "  - blocks:\n"
                         "      repeats: 100000\n"
                         "      rows:\n"
                         "        - {mean: 0.08, amplitude: 0.004, frequency: 2.0, cycles: 2}\n"
                         "        - {mean: 0.085, amplitude: 0.006, frequency: 2.0, cycles: 2}\n";
  BackgroundProcess rig({"/bin/sh", "-c",
                         "exec " + in_ns(kRigctl + " run " + config_ + " --operator --key " + key_ + " --lcm-url '" +
                                         kUrl + "' --log " + (dir_ / "run.lcm").string() + " --no-realtime --procedure " +
                                         proc + " --recovery " + recovery)},
                        (dir_ / "rig.out").string());
  ASSERT_TRUE(rig.wait_for("listening on RIGCTL_OPERATOR", 60.0)) << rig.output();
  auto step = [&](const std::string& command, const std::string& change) {
    const auto r = cmd(command, key_);
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.output;
    ASSERT_TRUE(wait_event(change)) << command << " did not give " << change << "\n" << read_file(events_) << rig.output();
  };
  auto cycles = [&] { return rigctl::read_recovery_file(recovery).recovery.status; };
  step("reset", "message=\"faulted -> off\"");
  step("hydraulics-low", "message=\"off -> hydraulics_low\"");
  step("hydraulics-high", "message=\"hydraulics_low -> hydraulics_high\"");
  // Not running yet: refused by the state table, with its reason.
  step("stop-at-block-end", "message=\"stop_at_block_end refused: the rig is not running\"");
  step("arm", "message=\"hydraulics_high -> armed\"");
  step("start", "message=\"armed -> running\"");
  ASSERT_TRUE(rigctl::test::wait_until([&] { return fs::exists(recovery) && cycles().total_cycles >= 1; }, 120.0))
      << rig.output();
  step("hold", "message=\"running -> holding\"");
  step("resume", "message=\"holding -> running\"");
  const int64_t before = cycles().total_cycles;
  ASSERT_TRUE(rigctl::test::wait_until([&] { return cycles().total_cycles > before; }, 120.0)) << rig.output();
  step("stop-at-block-end", "message=\"stop_at_block_end accepted\"");
  ASSERT_TRUE(wait_event("code=block_end_stop")) << read_file(events_);
  ASSERT_TRUE(wait_event("message=\"stopping -> hydraulics_high\"")) << read_file(events_);
  step("hydraulics-off", "message=\"hydraulics_high -> off\"");
  EXPECT_EQ(rig.wait(), 0) << rig.output();

  // Stopped at a whole pass; the recovery has the request done.
  const rigctl::ProcedureStatus at_stop = cycles();
  EXPECT_EQ(at_stop.total_cycles % 4, 0) << at_stop.total_cycles;
  EXPECT_GT(at_stop.total_cycles, before);
  EXPECT_EQ(at_stop.row, 0);
  EXPECT_EQ(at_stop.row_cycles, 0);
  EXPECT_FALSE(at_stop.stop_at_block_end);
  const std::string ev = read_file(events_);
  EXPECT_NE(ev.find("code=block_end_stop value=" + std::to_string(at_stop.total_cycles) + " "), std::string::npos) << ev;
  const auto changes = state_changes(ev);
  const std::vector<std::string> tail{"armed -> running", "running -> holding", "holding -> running", "running -> stopping",
                                      "stopping -> hydraulics_high", "hydraulics_high -> off"};
  ASSERT_GE(changes.size(), tail.size()) << ev;
  EXPECT_EQ(std::vector<std::string>(changes.end() - static_cast<std::ptrdiff_t>(tail.size()), changes.end()), tail) << ev;

  // Resumed from that recovery (simulated time, 10 s): no stop at the next
  // block end, the count goes on from the stop's.
  const auto resumed = run_command(kRigctl + " run " + config_ + " --fast --duration 10 --procedure " + proc +
                                   " --resume " + recovery + " --log " + (dir_ / "resumed.lcm").string() +
                                   " --recovery " + (dir_ / "resumed.recovery").string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const rigctl::ProcedureStatus after = rigctl::read_recovery_file((dir_ / "resumed.recovery").string()).recovery.status;
  EXPECT_GE(after.total_cycles, at_stop.total_cycles + 4) << resumed.output;
  EXPECT_EQ(read_file((dir_ / "resumed.lcm.events").string()).find("block_end_stop"), std::string::npos);
}

TEST(OperatorModeConfig, WithoutAKeyTheRunRefusesNamingTheField) {
  // The shipped config's key file (config/operator.key) is not in the tree.
  const auto r = run_command(kRigctl + " run " + kConfig + " --operator --fast --duration 0.1 --log /dev/null --events /dev/null");
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("operator.key"), std::string::npos) << r.output;
}

// The `operator:` section is read strictly: each error names its field.
std::string config_error(const std::string& from, const std::string& to) {
  std::string text = read_file(kConfig);
  const auto at = text.find(from);
  if (at == std::string::npos) return "config text '" + from + "' not found";
  text.replace(at, from.size(), to);
  try {
    rigctl::parse_rig_config(text, kConfig);
  } catch (const rigctl::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(OperatorModeConfig, ReaderNamesTheBadField) {
  EXPECT_NE(config_error("  staleness_s: 2.0", "  staleness_s: 2.0\n  bogus: 1").find("operator.bogus"), std::string::npos);
  EXPECT_NE(config_error("  key_file: operator.key", "").find("operator.key_file"), std::string::npos);
  EXPECT_NE(config_error("  staleness_s: 2.0", "  staleness_s: 600").find("operator.staleness_s"), std::string::npos);
  EXPECT_NE(config_error("  channel: RIGCTL_OPERATOR", "  channel: \"A.*\"").find("operator.channel"), std::string::npos);
  // Relative key paths are taken from the config's folder.
  const auto c = rigctl::parse_rig_config(read_file(kConfig), kConfig);
  EXPECT_EQ(c.operator_commands.key_file, (fs::path(kConfig).parent_path() / "operator.key").string());
  EXPECT_DOUBLE_EQ(c.operator_commands.staleness_s, 2.0);
}

}  // namespace
