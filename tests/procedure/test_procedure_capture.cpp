// A procedure's data capture (tools/procedure/capture_writer.hpp) from a
// `rigctl run --fast --procedure` of a 60-cycle sine on the quarter car,
// with a peak-valley detector so tight that it trips on the sensor noise
// (action indicate: the run goes on, so the trip has a post-trigger). The
// files are checked against each other and against the run's own log:
// every test cycle has its peaks and valleys, the log-spaced cycles 1, 2,
// 5, 10, 20 and 50 have their full-rate histories (whose extremes are the
// peaks file's), and the trip window holds exactly the ticks around the
// trip's, with the run log's values.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "read_file.hpp"
#include "rigctl/sample_t.hpp"
#include "tools/procedure/capture_writer.hpp"

namespace {

namespace fs = std::filesystem;
using rigctl::test::read_file;
using rigctl::test::run_command;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<int>(i);
    return -1;
  }
};

Csv read_csv(const fs::path& p) {
  Csv c;
  std::ifstream in(p);
  std::string line;
  auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::stringstream s(l);
    for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell);
    return out;
  };
  if (std::getline(in, line)) c.header = split(line);
  while (std::getline(in, line)) c.rows.push_back(split(line));
  return c;
}

class ProcedureCapture : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_capture_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST(LogSpacedCycles, AreOneTwoFiveInEveryDecade) {
  std::vector<int64_t> got;
  for (int64_t n = 0; n <= 1000; ++n)
    if (rigctl::log_spaced_cycle(n)) got.push_back(n);
  EXPECT_EQ(got, (std::vector<int64_t>{1, 2, 5, 10, 20, 50, 100, 200, 500, 1000}));
}

TEST_F(ProcedureCapture, PeaksEveryCycleLogSpacedHistoriesAndATripWindow) {
  std::ofstream(dir_ / "proc.yaml")
      << "ramp_rate: 0.02\n"
         "capture: {channels: [x_r, f_t], pre_trigger: 0.2, post_trigger: 0.3}\n"
         "steps:\n"
         "  - ramp: {level: 0.08, rate: 0.02}\n"
         "  - sine:\n"
         "      {mean: 0.08, amplitude: 0.002, frequency: 5, cycles: 60, compensation: amplitude_phase,\n"
         "       peak_valley_detector: {channel: x_r, tolerance: 0.0001, cycles: 1, action: indicate,\n"
         "                              settle_cycles: 5, reference_cycles: 2}}\n";
  const std::string log = (dir_ / "run.lcm").string();
  const auto r = run_command(kRigctl + " run " + kConfig + " --fast --procedure " + (dir_ / "proc.yaml").string() +
                             " --log " + log);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("capture: " + log + ".capture (60 cycles' peaks, 6 cycle histories, 1 trip windows)"),
            std::string::npos)
      << r.output;
  const fs::path cap = log + ".capture";

  // Every test cycle of the sine (step 1), numbered, with its extremes.
  const Csv peaks = read_csv(cap / "peaks.csv");
  ASSERT_EQ(peaks.rows.size(), 60u);
  const int xp = peaks.column("x_r_peak"), xv = peaks.column("x_r_valley"), fp = peaks.column("f_t_peak");
  ASSERT_GE(xp, 0);
  ASSERT_GE(fp, 0);
  for (std::size_t i = 0; i < peaks.rows.size(); ++i) {
    const auto& row = peaks.rows[i];
    EXPECT_EQ(row[0], "1");
    EXPECT_EQ(row[2], std::to_string(i + 1));
    EXPECT_EQ(row[3], std::to_string(i + 1));
    const double range = std::stod(row[static_cast<std::size_t>(xp)]) - std::stod(row[static_cast<std::size_t>(xv)]);
    // From cycle 20 the compensated 2 mm sine is within a few % of its 4 mm range (sensor noise on top).
    if (i >= 19) EXPECT_NEAR(range, 0.004, 0.0004) << "cycle " << i + 1;
  }

  // The log-spaced histories: one cycle each (5 Hz at 2.5 ms: 80 ticks),
  // consecutive ticks, and x_r's extremes there are the peaks file's.
  for (int n : {1, 2, 5, 10, 20, 50}) {
    const Csv h = read_csv(cap / ("cycle-1-" + std::to_string(n) + ".csv"));
    ASSERT_EQ(h.rows.size(), 80u) << "cycle " << n;
    const int x = h.column("x_r");
    ASSERT_GE(x, 0);
    double hi = -1e9, lo = 1e9;
    for (std::size_t i = 0; i < h.rows.size(); ++i) {
      if (i > 0) EXPECT_EQ(std::stoll(h.rows[i][1]), std::stoll(h.rows[i - 1][1]) + 1) << "cycle " << n;
      hi = std::max(hi, std::stod(h.rows[i][static_cast<std::size_t>(x)]));
      lo = std::min(lo, std::stod(h.rows[i][static_cast<std::size_t>(x)]));
    }
    const auto& row = peaks.rows[static_cast<std::size_t>(n - 1)];
    EXPECT_EQ(hi, std::stod(row[static_cast<std::size_t>(xp)])) << "cycle " << n;
    EXPECT_EQ(lo, std::stod(row[static_cast<std::size_t>(xv)])) << "cycle " << n;
  }
  EXPECT_FALSE(fs::exists(cap / "cycle-1-3.csv"));

  // The trip: its tick from the event log; 0.2 s before it (80 ticks), its
  // own tick, 0.3 s after (120 ticks), the values the run log has.
  std::smatch m;
  const std::string events = read_file(log + ".events");
  ASSERT_TRUE(std::regex_search(events, m, std::regex(R"(tick=(\d+) state=\w+ code=peak_valley_change)"))) << events;
  const long long trip = std::stoll(m[1]);
  const fs::path window = cap / ("trip-" + std::to_string(trip) + "-peak_valley_change.csv");
  const Csv w = read_csv(window);
  ASSERT_EQ(w.rows.size(), 80u + 1u + 120u) << window;
  EXPECT_EQ(std::stoll(w.rows.front()[1]), trip - 80);
  EXPECT_EQ(std::stoll(w.rows.back()[1]), trip + 120);
  std::map<long long, double> logged;  // x_r by tick, from the run log
  lcm::LogFile lf(log, "r");
  ASSERT_TRUE(lf.good());
  while (const lcm::LogEvent* e = lf.readNextEvent()) {
    if (e->channel != "RIGCTL_SAMPLE") continue;
    rigctl::sample_t s;
    ASSERT_GE(s.decode(e->data, 0, e->datalen), 0);
    if (s.tick >= trip - 80 && s.tick <= trip + 120) logged[s.tick] = s.values[0];  // x_r is input 0
  }
  const int x = w.column("x_r");
  ASSERT_EQ(x, 2);
  for (std::size_t i = 0; i < w.rows.size(); ++i) {
    const long long tick = std::stoll(w.rows[i][0 + 1]);
    EXPECT_EQ(tick, trip - 80 + static_cast<long long>(i));
    ASSERT_EQ(logged.count(tick), 1u) << tick;
    EXPECT_NEAR(std::stod(w.rows[i][static_cast<std::size_t>(x)]), logged[tick], 1e-9 * std::fabs(logged[tick]) + 1e-12);
  }
}

}  // namespace
