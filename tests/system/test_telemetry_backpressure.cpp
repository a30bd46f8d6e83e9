// What a full telemetry queue does in a whole run of the program. The run's
// log is a named pipe whose reader the test controls, so the log sink is as
// slow as the test wants:
// * in simulated time (--fast) the loop waits for the publisher and the log
//   is identical to a paced run's, with nothing dropped (backpressure);
// * a paced run never waits: records are dropped, counted and the count is
//   published, and the loop keeps its ticks.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "log_messages.hpp"
#include "process.hpp"
#include "rigctl/timing_t.hpp"

namespace {

namespace fs = std::filesystem;
using rigctl::test::data_messages;
using rigctl::test::run_command;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

// The reading end of a named pipe that the run writes its LCM log into.
// Copies what it reads into a regular file; reads `chunk` bytes at a time
// with `pause` between reads, and after the first bytes arrive reads nothing
// for `stall` (a disk that hangs). Ends when the writer closes the pipe.
class SlowLogReader {
 public:
  SlowLogReader(const std::string& fifo, const std::string& copy, std::size_t chunk,
                std::chrono::microseconds pause, std::chrono::milliseconds stall)
      : copy_(copy, std::ios::binary), chunk_(chunk), pause_(pause), stall_(stall) {
    if (::mkfifo(fifo.c_str(), 0600) != 0) throw std::runtime_error("mkfifo " + fifo);
    // Non-blocking: the open succeeds before any writer exists.
    fd_ = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error("open " + fifo);
    thread_ = std::thread([this] { read_all(); });
  }
  ~SlowLogReader() {
    finish();
    ::close(fd_);
  }
  // After the run's process has exited: the reader takes what is left in the
  // pipe and ends, also when the run failed before it opened its log.
  void finish() {
    writer_gone_ = true;
    if (thread_.joinable()) thread_.join();
    copy_.flush();
  }

 private:
  void read_all() {
    std::vector<char> buf(chunk_);
    bool writer_seen = false, stalled = false;
    for (;;) {
      const ssize_t n = ::read(fd_, buf.data(), buf.size());
      if (n > 0) {
        writer_seen = true;
        copy_.write(buf.data(), n);
        if (!stalled && stall_.count() > 0) std::this_thread::sleep_for(stall_);
        stalled = true;
        if (pause_.count() > 0) std::this_thread::sleep_for(pause_);
      } else if (n < 0 && errno == EAGAIN) {
        writer_seen = true;  // a writer holds the pipe open, nothing to read yet
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      } else if (n == 0 && (writer_seen || writer_gone_)) {
        return;  // the writer closed the log (or never opened it)
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // the run has not opened its log yet
      }
    }
  }

  std::ofstream copy_;
  std::size_t chunk_;
  std::chrono::microseconds pause_;
  std::chrono::milliseconds stall_;
  int fd_ = -1;
  std::atomic<bool> writer_gone_{false};
  std::thread thread_;
};

std::vector<rigctl::timing_t> timing_messages(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  std::vector<rigctl::timing_t> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "RIGCTL_TIMING") continue;
    rigctl::timing_t m;
    if (m.decode(e->data, 0, e->datalen) >= 0) out.push_back(m);
  }
  return out;
}

int64_t number_after(const std::string& text, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(pattern))) return -1;
  return std::stoll(m[1].str());
}

class TelemetryBackpressure : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigctl_backpressure_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(TelemetryBackpressure, FastRunWithASlowLogLosesNothingAndMatchesThePacedRun) {
  const auto paced = run_command(kRigctl + " run " + kConfig + " --duration 1 --log " + path("paced.lcm"));
  ASSERT_EQ(paced.exit_code, 0) << paced.output;

  // A queue of 4 records and a log that takes 1 kB per millisecond: the
  // loop (tens of thousands of ticks a second in simulated time) outruns it
  // at once and must wait for it all the way through.
  std::string fast_output;
  {
    SlowLogReader reader(path("fast.fifo"), path("fast.lcm"), 1024, std::chrono::milliseconds(1),
                         std::chrono::milliseconds(0));
    const auto fast = run_command(kRigctl + " run " + kConfig + " --duration 1 --fast --telemetry-queue 4 --log " +
                                  path("fast.fifo"));
    reader.finish();
    ASSERT_EQ(fast.exit_code, 0) << fast.output;
    fast_output = fast.output;
  }
  EXPECT_NE(fast_output.find("holds the loop back"), std::string::npos) << fast_output;
  EXPECT_GT(number_after(fast_output, R"(telemetry queue full (\d+) times)"), 0)
      << "the queue never filled: the test did not exercise backpressure\n" << fast_output;
  EXPECT_EQ(fast_output.find("records dropped"), std::string::npos) << fast_output;

  const auto a = data_messages(path("paced.lcm"));
  const auto b = data_messages(path("fast.lcm"));
  EXPECT_EQ(a.size(), 3u * 400u);  // 1 s at 400 Hz, three data channels
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "message " << i << " differs";

  const auto timing = timing_messages(path("fast.lcm"));
  ASSERT_FALSE(timing.empty());
  EXPECT_EQ(timing.back().queue_policy, "wait");
  EXPECT_EQ(timing.back().dropped_records, 0);
  EXPECT_EQ(timing_messages(path("paced.lcm")).back().queue_policy, "drop");
}

TEST_F(TelemetryBackpressure, PacedRunWithAStalledLogDropsAndCountsButNeverWaits) {
  // 400 records a second fill the pipe's 64 kB and a queue of 8 records in
  // about a quarter of a second; the log then hangs for 1.5 s more. A loop
  // that waited would miss every tick of that (~500); one that drops keeps
  // its deadlines.
  std::string output;
  {
    SlowLogReader reader(path("paced.fifo"), path("paced.lcm"), 1 << 16, std::chrono::microseconds(0),
                         std::chrono::milliseconds(1500));
    const auto run = run_command(kRigctl + " run " + kConfig + " --duration 3 --telemetry-queue 8 --log " +
                                 path("paced.fifo"));
    reader.finish();
    ASSERT_EQ(run.exit_code, 0) << run.output;
    output = run.output;
  }
  EXPECT_NE(output.find("drops and counts"), std::string::npos) << output;
  const int64_t ticks = number_after(output, R"(after (\d+) ticks)");
  const int64_t dropped = number_after(output, R"(telemetry records dropped: (\d+))");
  const int64_t missed = number_after(output, R"(missed ticks (\d+))");
  ASSERT_GT(ticks, 0) << output;
  EXPECT_GT(dropped, 100) << output;
  // Only a loop at real-time priority keeps its deadlines beside a CPU hog;
  // without SCHED_FIFO (not root) the bound would measure the scheduler.
  if (!std::regex_search(output, std::regex(R"(SCHED_FIFO priority \d+ refused)"))) {
    EXPECT_LT(missed, 250) << "the loop waited for the stalled log\n" << output;
  }

  // Every record is either in the log or counted as dropped (the closing
  // record has no sample); the published count agrees with the console's.
  int64_t samples = 0;
  for (const auto& m : data_messages(path("paced.lcm"))) samples += m.rfind("RIGCTL_SAMPLE:", 0) == 0;
  EXPECT_GE(samples + dropped, ticks);
  EXPECT_LE(samples + dropped, ticks + 1);
  const auto timing = timing_messages(path("paced.lcm"));
  ASSERT_FALSE(timing.empty());
  EXPECT_EQ(timing.back().queue_policy, "drop");
  EXPECT_EQ(timing.back().dropped_records, dropped);
}

}  // namespace
