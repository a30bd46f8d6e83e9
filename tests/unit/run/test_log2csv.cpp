// log_to_csv: a log written by TelemetryPublisher becomes a run file of
// docs/run-files.md with the right metadata, header and values;
// ticks missing a message are skipped and counted; bad inputs throw naming
// the file and leave no output behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/command_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "tools/runfile/log2csv.hpp"

namespace fs = std::filesystem;
using namespace rigctl;

namespace {

constexpr int64_t kPeriodNs = 2'500'000;  // 400 Hz
const std::vector<std::string> kInputs = {"x_r", "x_w", "x_b", "v_w", "v_b", "p1", "p2", "f_t", "sim_x_b"};

// Values of widely different magnitude (m, Pa, N), so formatting is tested.
double input_value(int64_t tick, std::size_t i) {
  const double s = std::sin(0.05 * static_cast<double>(tick) + static_cast<double>(i));
  switch (i) {
    case 5: case 6: return 2.0e6 + 1.0e5 * s;  // pressures [Pa]
    case 7: return 3000.0 * s;                   // tyre force [N]
    default: return 0.01 * s / 3.0;              // displacements and velocities
  }
}
double setpoint_value(int64_t tick) { return 0.02 * std::sin(0.01 * static_cast<double>(tick)) + 1e-7; }
double output_value(int64_t tick) { return -0.3 + 1e-3 * static_cast<double>(tick) / 7.0; }

TelemetryMeta quarter_car_meta() {
  TelemetryMeta m;
  m.rig = "quarter_car";
  for (const auto& n : kInputs) m.layout.inputs.push_back({n, "m"});
  m.layout.outputs = {{"u", "1"}};
  m.setpoint_name = "x_ref";
  m.controller_name = "pi";
  m.term_names = {"p", "i"};
  m.start_utime = 1'700'000'000'000'000;
  return m;
}

struct Csv {
  std::vector<std::string> meta;  // "# ..." lines
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
};

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

Csv read_csv(const fs::path& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("#", 0) == 0) {
      csv.meta.push_back(line);
    } else if (csv.header.empty()) {
      csv.header = split(line);
    } else {
      std::vector<double> row;
      for (const auto& cell : split(line)) {
        char* end = nullptr;
        row.push_back(std::strtod(cell.c_str(), &end));
        EXPECT_EQ(*end, '\0') << "not a number: '" << cell << "'";
      }
      csv.rows.push_back(row);
    }
  }
  return csv;
}

// |a - b| within what 9 significant digits allow.
::testing::AssertionResult close9(double got, double want) {
  if (std::fabs(got - want) <= 5e-9 * std::fabs(want) + 1e-300) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << got << " vs " << want;
}

class Log2CsvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_test_log2csv_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Only the output file itself may be left in dir_ (no temp files).
  std::vector<std::string> files() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
  }
  fs::path dir_;
};

TEST_F(Log2CsvTest, PublisherLogBecomesRunFile) {
  const fs::path log = dir_ / "run.lcm";
  const fs::path csv = dir_ / "run.csv";
  constexpr int64_t kTicks = 300;
  {
    TelemetryPublisher pub(quarter_car_meta(), "memq://", log.string(), 1024);
    for (int64_t k = 0; k < kTicks; ++k) {
      TelemetryRecord r;
      r.tick = k;
      r.sample.t_ns = k * kPeriodNs;
      for (std::size_t i = 0; i < kInputs.size(); ++i) r.sample.value[i] = input_value(k, i);
      r.command.value[0] = output_value(k);
      r.controller.setpoint = setpoint_value(k);
      r.has_timing = k == 100;  // other channels in the log must be ignored
      ASSERT_TRUE(pub.push(r));
    }
    pub.stop();  // no thread: stop() publishes everything in this thread
  }

  const Log2CsvResult res = log_to_csv(log.string(), csv.string());
  EXPECT_EQ(res.rows, kTicks);
  EXPECT_EQ(res.skipped, 0);
  EXPECT_EQ(res.rig, "quarter_car");
  EXPECT_EQ(files(), (std::vector<std::string>{"run.csv", "run.lcm"}));

  const Csv c = read_csv(csv);
  EXPECT_EQ(c.meta, (std::vector<std::string>{"# rig: quarter_car", "# sample_rate_hz: 400",
                                              "# source: rigctl log2csv run.lcm",
                                              "# telemetry_queue_policy: drop", "# dropped_records: 0"}));
  const std::vector<std::string> header = {"t", "x_ref", "u", "x_r", "x_w", "x_b", "v_w",
                                           "v_b", "p1", "p2", "f_t", "sim_x_b"};
  ASSERT_EQ(c.header, header);
  ASSERT_EQ(c.rows.size(), static_cast<std::size_t>(kTicks));
  for (int64_t k = 0; k < kTicks; ++k) {
    const std::vector<double>& row = c.rows[k];
    ASSERT_EQ(row.size(), header.size()) << "row " << k;
    EXPECT_NEAR(row[0], static_cast<double>(k) * 2.5e-3, 1e-12) << "row " << k;
    if (k > 0) {
      EXPECT_GT(row[0], c.rows[k - 1][0]) << "t not strictly increasing at row " << k;
    }
    EXPECT_TRUE(close9(row[1], setpoint_value(k))) << "x_ref row " << k;
    EXPECT_TRUE(close9(row[2], output_value(k))) << "u row " << k;
    for (std::size_t i = 0; i < kInputs.size(); ++i) {
      EXPECT_TRUE(close9(row[3 + i], input_value(k, i))) << kInputs[i] << " row " << k;
    }
  }
}

// A hand-made log with a custom prefix: commands missing on two ticks, one
// invalid sample, and a stray event on another channel.
TEST_F(Log2CsvTest, TicksMissingAMessageAreSkippedAndCounted) {
  const fs::path log_path = dir_ / "gappy.lcm";
  {
    lcm::LogFile log(log_path.string(), "w");
    ASSERT_TRUE(log.good());
    auto write = [&](const std::string& ch, auto& msg) {
      std::vector<uint8_t> buf(msg.getEncodedSize());
      msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent ev{0, msg.utime, ch, static_cast<int32_t>(buf.size()), buf.data()};
      ASSERT_EQ(log.writeEvent(&ev), 0);
    };
    for (int64_t k = 0; k < 10; ++k) {
      sample_t s{};
      s.utime = k * 1000;
      s.tick = k;
      s.t = k * 1e-3;
      s.rig = "damper";
      s.status = k == 5 ? 1 : 0;  // driver flagged an input invalid
      s.num_channels = 2;
      s.names = {"x", "f"};
      s.units = {"m", "N"};
      s.values = {0.001 * k, 10.0 * k};
      write("X_SAMPLE", s);
      write("X_OTHER", s);
      if (k == 3 || k == 7) continue;
      command_t c{};
      c.utime = s.utime;
      c.tick = k;
      c.t = s.t;
      c.setpoint_name = "x_d";
      c.setpoint = 0.5;
      c.num_outputs = 1;
      c.names = {"u"};
      c.units = {"V"};
      c.values = {1.0};
      write("X_COMMAND", c);
    }
  }
  const fs::path csv = dir_ / "gappy.csv";
  const Log2CsvResult res = log_to_csv(log_path.string(), csv.string(), "X_");
  EXPECT_EQ(res.rows, 7);
  EXPECT_EQ(res.skipped, 3);
  EXPECT_EQ(res.rig, "damper");
  const Csv c = read_csv(csv);
  EXPECT_EQ(c.header, (std::vector<std::string>{"t", "x_d", "u", "x", "f"}));
  std::vector<double> t;
  for (const auto& row : c.rows) t.push_back(row[0]);
  EXPECT_EQ(t, (std::vector<double>{0.0, 0.001, 0.002, 0.004, 0.006, 0.008, 0.009}));
  EXPECT_EQ(c.meta.at(1), "# sample_rate_hz: 1000");
}

void expect_throw_naming(const std::string& log, const std::string& csv, const std::string& reason) {
  try {
    log_to_csv(log, csv);
    ADD_FAILURE() << "no exception for " << log;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(log), std::string::npos) << "message does not name the file: " << what;
    EXPECT_NE(what.find(reason), std::string::npos) << "message does not give the reason '" << reason << "': " << what;
  }
}

TEST_F(Log2CsvTest, MissingFileThrowsNamingIt) {
  expect_throw_naming((dir_ / "nope.lcm").string(), (dir_ / "out.csv").string(), "no such file");
  EXPECT_TRUE(files().empty());
}

TEST_F(Log2CsvTest, NotAnLcmLogThrowsNamingIt) {
  const fs::path bogus = dir_ / "notes.lcm";
  std::ofstream(bogus) << "t,x_ref,u\n0,0,0\n";
  expect_throw_naming(bogus.string(), (dir_ / "out.csv").string(), "not an LCM log");
  EXPECT_EQ(files(), std::vector<std::string>{"notes.lcm"});
}

TEST_F(Log2CsvTest, LogWithoutSamplesThrowsAndLeavesNoFile) {
  const fs::path log_path = dir_ / "empty_run.lcm";
  {
    lcm::LogFile log(log_path.string(), "w");
    uint8_t byte = 0;
    lcm::LogEvent ev{0, 1, "SOMETHING_ELSE", 1, &byte};
    ASSERT_EQ(log.writeEvent(&ev), 0);
  }
  expect_throw_naming(log_path.string(), (dir_ / "out.csv").string(), "no sample messages");
  EXPECT_EQ(files(), std::vector<std::string>{"empty_run.lcm"});
}

}  // namespace
