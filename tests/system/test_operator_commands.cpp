// Operator commands (issue 7), the parts outside the verifier (which
// tests/unit/rt/test_operator_auth.cpp covers): key files are refused when
// others could read them; the sequence state survives between invocations;
// and end to end, `rigctl cmd` (a separate process) reaches a CommandReceiver
// in this process over the real udpm:// provider inside a network namespace
// this test creates, and the ack comes back. Nothing here sends or joins
// multicast in the host's namespace.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/state_t.hpp"
#include "tests/support/process.hpp"
#include "tests/support/test_netns.hpp"
#include "tools/cmd/cmd_command.hpp"
#include "rt/comms/command_receiver.hpp"
#include "rt/comms/operator_auth.hpp"
#include "tests/support/operator_commands.hpp"

namespace fs = std::filesystem;
using namespace rigctl;
using namespace rigctl::test;

namespace {

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("rigctl_test_opcmd_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

std::string write_key(const fs::path& path, std::size_t size, mode_t mode, uint8_t fill = 0x5a) {
  {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    const std::string bytes(size, static_cast<char>(fill));
    f << bytes;
  }
  ::chmod(path.c_str(), mode);
  return path.string();
}

// The text of the exception load_operator_key throws, or "" if it loads.
std::string key_error(const std::string& path) {
  try {
    load_operator_key(path);
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

// ---------------------------------------------------------------- key files

TEST(OperatorKeyFile, RefusesKeysOthersCouldReadOrThatAreTooShort) {
  TempDir dir;
  const std::string good = write_key(dir.path() / "good", 32, 0600);
  EXPECT_EQ(key_error(good), "");
  EXPECT_EQ(load_operator_key(good).size(), 32u);
  EXPECT_EQ(key_error(write_key(dir.path() / "readonly", 32, 0400)), "");

  for (mode_t mode : {0644, 0640, 0604, 0620, 0602, 0610}) {
    const std::string p = write_key(dir.path() / ("mode" + std::to_string(mode)), 32, mode);
    const std::string e = key_error(p);
    EXPECT_NE(e.find(p), std::string::npos) << "mode " << std::oct << mode << ": " << e;
    EXPECT_NE(e.find("group or others"), std::string::npos) << e;
    EXPECT_NE(e.find("chmod 600"), std::string::npos) << e;
  }
  const std::string short_key = write_key(dir.path() / "short", 31, 0600);
  const std::string e = key_error(short_key);
  EXPECT_NE(e.find(short_key), std::string::npos) << e;
  EXPECT_NE(e.find("31 bytes"), std::string::npos) << e;
  EXPECT_NE(e.find("at least 32"), std::string::npos) << e;

  const std::string missing = (dir.path() / "missing").string();
  EXPECT_NE(key_error(missing).find(missing), std::string::npos);
  EXPECT_NE(key_error(missing).find("No such file"), std::string::npos) << key_error(missing);
  fs::create_symlink(good, dir.path() / "link");
  EXPECT_NE(key_error((dir.path() / "link").string()).find("symbolic link"), std::string::npos);
  ::chmod(dir.path().c_str(), 0700);
  EXPECT_NE(key_error(dir.path().string()).find("not a regular file"), std::string::npos);
}

TEST(OperatorKeyFile, RefusesKeysOfAnotherUserOrInAFolderOthersMayWrite) {
  TempDir dir;
  const fs::path open_dir = dir.path() / "open";
  fs::create_directories(open_dir);
  ::chmod(open_dir.c_str(), 0777);  // anyone could put a key of their own here
  const std::string in_open = write_key(open_dir / "rig.key", 32, 0600);
  const std::string e = key_error(in_open);
  EXPECT_NE(e.find("another user could replace it"), std::string::npos) << e;
  EXPECT_NE(e.find("0777"), std::string::npos) << e;
  ::chmod(open_dir.c_str(), 01777);  // sticky, as /tmp: only a file's owner may remove or rename it
  EXPECT_EQ(key_error(in_open), "");
  ::chmod(open_dir.c_str(), 0770);
  EXPECT_NE(key_error(in_open).find("another user could replace it"), std::string::npos);
  ::chmod(open_dir.c_str(), 0700);
  EXPECT_EQ(key_error(in_open), "");
  if (::geteuid() != 0) GTEST_SKIP() << "changing a file's owner needs root";
  const std::string theirs = write_key(dir.path() / "theirs.key", 32, 0600);
  ASSERT_EQ(::chown(theirs.c_str(), 65534, 65534), 0);  // nobody's
  const std::string t = key_error(theirs);
  EXPECT_NE(t.find("owned by uid 65534"), std::string::npos) << t;
  ASSERT_EQ(::chown(open_dir.c_str(), 65534, 65534), 0);  // a folder another user owns
  EXPECT_NE(key_error(in_open).find("owner uid 65534"), std::string::npos) << key_error(in_open);
}

TEST(SequenceState, SurvivesBetweenInvocationsAndNeverGoesBack) {
  TempDir dir;
  const std::string path = (dir.path() / "sub" / "alice.seq").string();
  const int64_t a = reserve_sequence(path, 1000);
  EXPECT_EQ(a, 1000);
  EXPECT_EQ(reserve_sequence(path, 1000), 1001);  // same microsecond: still higher
  EXPECT_EQ(reserve_sequence(path, 10), 1002);    // clock stepped back: the file wins
  EXPECT_EQ(reserve_sequence(path, 5000), 5000);  // clock ahead: the clock wins
  struct stat st{};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  {
    std::ofstream f(path, std::ios::trunc);
    f << "garbage\n";
  }
  try {
    reserve_sequence(path, 1);
    ADD_FAILURE() << "garbage state file accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------- the program, without a bus

std::string binary() { return RIGCTL_BINARY; }

TEST(RigctlCmd, RefusesBadKeyFilesAndUsageBeforeSendingAnything) {
  TempDir dir;
  const std::string open_key = write_key(dir.path() / "open.key", 32, 0644);
  const std::string key = write_key(dir.path() / "key", 32, 0600);
  const std::string common = " --lcm-url memq:// --state-file " + (dir.path() / "seq").string();
  auto r = test::run_command(binary() + " cmd arm --key " + open_key + common);
  EXPECT_EQ(r.exit_code, kCmdError) << r.output;
  EXPECT_NE(r.output.find(open_key), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("group or others"), std::string::npos) << r.output;

  r = test::run_command(binary() + " cmd launch --key " + key + common);
  EXPECT_EQ(r.exit_code, kCmdUsage) << r.output;
  EXPECT_NE(r.output.find("unknown command 'launch'"), std::string::npos) << r.output;
  r = test::run_command(binary() + " cmd setpoint --key " + key + common);
  EXPECT_EQ(r.exit_code, kCmdUsage) << r.output;
  r = test::run_command(binary() + " cmd setpoint nan --key " + key + common);
  EXPECT_EQ(r.exit_code, kCmdUsage) << r.output;
  r = test::run_command(binary() + " cmd arm 3 --key " + key + common);
  EXPECT_EQ(r.exit_code, kCmdUsage) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "seq")) << "a sequence was used up by a refused command";
  // memq:// has no rig on it: sent, no acknowledgement.
  r = test::run_command(binary() + " cmd hold --key " + key + common + " --wait-ack 0.2");
  EXPECT_EQ(r.exit_code, kCmdNoAck) << r.output;
  EXPECT_NE(r.output.find("no acknowledgement on RIGCTL_OPERATOR_ACK"), std::string::npos) << r.output;
}

// ---------------------------------------------------------------- end to end over udpm://

constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

// Receives acks on the test's side (for the raw replays below).
struct AckLog {
  std::vector<operator_ack_t> acks;
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    operator_ack_t a;
    if (decode_operator_ack(rbuf->data, rbuf->data_size, a)) acks.push_back(a);
  }
};

class OperatorCommandsUdpm : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!ns_.ready()) GTEST_SKIP() << ns_.skip_reason();
  }

  std::string enter_namespace() const { return ns_.enter_this_thread(); }

  test::ProcessResult rigctl_cmd(const std::string& args) const {
    return test::run_command(ns_.exec_prefix() + binary() + " cmd " + args + " --lcm-url '" + kUrl + "'");
  }

  test::TestNetns ns_{"opcmd"};
};

// Pops what the receiver queued, until `want` commands or `timeout`.
std::vector<OperatorCommand> drain(CommandReceiver& rx, std::size_t want, std::chrono::milliseconds timeout) {
  std::vector<OperatorCommand> out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  OperatorCommand c;
  while (out.size() < want && std::chrono::steady_clock::now() < deadline) {
    if (rx.queue().try_pop(c)) {
      out.push_back(c);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  return out;
}

TEST_F(OperatorCommandsUdpm, RigctlCmdReachesTheReceiverAndTheAckComesBack) {
  TempDir dir;
  const std::string key = write_key(dir.path() / "rig.key", 32, 0600, 0x11);
  const std::string wrong_key = write_key(dir.path() / "wrong.key", 32, 0600, 0x22);
  const std::string common = " --key " + key + " --sender op1 --state-file " + (dir.path() / "op1.seq").string();

  // Everything with sockets runs in a thread inside the namespace: setns
  // changes only the calling thread, and the receiver's thread inherits it.
  std::string error = "thread did not run";
  std::thread t([&] {
    error = enter_namespace();
    if (!error.empty()) return;
    CommandReceiverOptions opt;
    opt.lcm_url = kUrl;
    opt.channel = "RIGCTL_OPERATOR";
    opt.key_path = key;
    opt.policy = policy();
    // A command is stamped before a loaded machine gets it to the receiver:
    // 30 s, not 2 s, of age allowed here (the window is tested above).
    opt.policy.max_age_us = 30'000'000;
    opt.queue_capacity = 2;
    CommandReceiver rx(opt);
    rx.start();

    // 1. A valid command: accepted, queued, acknowledged. `rigctl cmd`
    //    returns at the ack: its wait is a deadline for a receiver that
    //    never answers.
    auto r = rigctl_cmd("arm" + common + " --wait-ack 30");
    EXPECT_EQ(r.exit_code, kCmdAccepted) << r.output;
    EXPECT_NE(r.output.find("accepted by the rig"), std::string::npos) << r.output;
    auto got = drain(rx, 1, std::chrono::seconds(30));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].kind, OperatorCommandKind::kArm);
    const uint64_t first_sequence = got[0].sequence;

    // 2. A setpoint within the limits; the sequence went up between invocations.
    r = rigctl_cmd("setpoint 0.02" + common + " --wait-ack 30");
    EXPECT_EQ(r.exit_code, kCmdAccepted) << r.output;
    got = drain(rx, 1, std::chrono::seconds(30));
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].kind, OperatorCommandKind::kSetpoint);
    EXPECT_EQ(got[0].value, 0.02);
    EXPECT_GT(got[0].sequence, first_sequence);

    // 3. Out of limits: the rig says so, and the exit code says rejected.
    r = rigctl_cmd("setpoint 0.2" + common + " --wait-ack 30");
    EXPECT_EQ(r.exit_code, kCmdRejected) << r.output;
    EXPECT_NE(r.output.find("rejected by the rig: out_of_limits"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("0.2 m outside [-0.05, 0.05] m"), std::string::npos) << r.output;

    // 4. The wrong key: counted as bad_tag; the rig's reply does not verify
    //    with the sender's key, so the sender reports no acknowledgement.
    //    It waits its whole --wait-ack for one that verifies: 5 s, for the
    //    reply that does not to arrive within it on a loaded machine.
    r = rigctl_cmd("start --key " + wrong_key + " --sender op2 --state-file " + (dir.path() / "op2.seq").string() + " --wait-ack 5");
    EXPECT_EQ(r.exit_code, kCmdNoAck) << r.output;
    EXPECT_NE(r.output.find("different key"), std::string::npos) << r.output;

    // 5. A replay from the network: the same bytes twice, then a full queue.
    lcm::LCM bus(kUrl);
    AckLog acks;
    bus.subscribe("RIGCTL_OPERATOR_ACK", &AckLog::on_message, &acks);
    const OperatorKey k = load_operator_key(key);
    const int64_t now = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
    const auto hold = signed_bytes(command("hold", 1, 0.0, now, "raw"), k);
    for (int i = 0; i < 2; ++i) bus.publish("RIGCTL_OPERATOR", hold.data(), static_cast<unsigned int>(hold.size()));
    for (int64_t s = 2; s <= 3; ++s) {  // the queue holds 2: hold + resume fill it, stop finds it full
      const auto b = signed_bytes(command(s == 3 ? "stop" : "resume", s, 0.0, now, "raw"), k);
      bus.publish("RIGCTL_OPERATOR", b.data(), static_cast<unsigned int>(b.size()));
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (acks.acks.size() < 4 && std::chrono::steady_clock::now() < deadline) bus.handleTimeout(50);
    ASSERT_EQ(acks.acks.size(), 4u);
    EXPECT_TRUE(acks.acks[0].accepted);
    EXPECT_EQ(acks.acks[1].reason, "replayed");
    EXPECT_FALSE(acks.acks[1].accepted);
    EXPECT_TRUE(acks.acks[2].accepted);
    EXPECT_EQ(acks.acks[3].reason, "queue_full");
    for (const auto& a : acks.acks) EXPECT_TRUE(tag_valid(a, k)) << "ack for sequence " << a.sequence;
    // The four acks say the receiver has handled all four: what it queued is final.
    got = drain(rx, 3, std::chrono::milliseconds(500));
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0].kind, OperatorCommandKind::kHold);
    EXPECT_EQ(got[1].kind, OperatorCommandKind::kResume);

    rx.stop();
    EXPECT_EQ(rx.counters().accepted(), 4u);  // arm, setpoint, hold, resume
    EXPECT_EQ(rx.counters().get(RejectReason::kOutOfLimits), 1u);
    EXPECT_EQ(rx.counters().get(RejectReason::kBadTag), 1u);
    EXPECT_EQ(rx.counters().get(RejectReason::kReplayed), 1u);
    EXPECT_EQ(rx.counters().get(RejectReason::kQueueFull), 1u);
    EXPECT_EQ(rx.counters().rejected(), 4u);
    EXPECT_EQ(rx.acks_sent(), 8u);
  });
  t.join();
  ASSERT_EQ(error, "");
}

}  // namespace
