// `rigctl log2mcap`: a run's LCM log as MCAP, read back by @mcap/core
// (tests/node/mcap_read.cjs) through the file's summary and indexes, as
// Foxglove and PlotJuggler read it: as many messages per channel as the LCM
// log has, every one valid JSON against its channel's schema, the summary's
// statistics right, the CRCs right. A log cut short gives the MCAP of what
// was readable and a warning.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "foxglove/telemetry/telemetry_json.hpp"
#include "node_client.hpp"
#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using namespace rigctl::test;

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

// What the LCM log holds, as log2mcap should carry it over.
struct LogContents {
  std::map<std::string, int64_t> counts;  // telemetry channel -> events
  int64_t total = 0;
  uint64_t min_time_ns = UINT64_MAX, max_time_ns = 0;
};

LogContents read_log(const std::string& path) {
  const rigctl::foxglove::TelemetryTopics topics("RIGCTL_");
  lcm::LogFile log(path, "r");
  LogContents c;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    const auto topic = topics.topic_of(e->channel);
    if (!topic) continue;
    const auto m = rigctl::foxglove::decode_telemetry(*topic, static_cast<const uint8_t*>(e->data), e->datalen);
    if (!m) continue;
    ++c.counts[e->channel];
    ++c.total;
    c.min_time_ns = std::min(c.min_time_ns, rigctl::foxglove::log_time_ns(*m));
    c.max_time_ns = std::max(c.max_time_ns, rigctl::foxglove::log_time_ns(*m));
  }
  return c;
}

class Log2Mcap : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_log2mcap_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // A run in simulated time with a limit trip at 2.5 s: samples, commands,
    // controller terms, timing and the state changes of an interlock.
    const auto run = run_command(kRigctl + " run " + kConfig + " --fast --duration 4 --fault offset@2.5:x_r:0.3 --log " +
                                 path("run.lcm"));
    ASSERT_EQ(run.exit_code, 3) << run.output;  // ended faulted
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Converts and reads back; returns the reader's findings.
  nlohmann::json convert_and_read(const std::string& log, const std::string& mcap, std::string* output = nullptr) {
    const auto conv = run_command(kRigctl + " log2mcap " + log + " " + mcap);
    EXPECT_EQ(conv.exit_code, 0) << conv.output;
    if (output != nullptr) *output = conv.output;
    const auto read = run_command(node_command("mcap_read.cjs", {mcap, mcap + ".json"}));
    EXPECT_EQ(read.exit_code, 0) << read.output;
    return read_json(mcap + ".json");
  }

  void expect_matches_log(const nlohmann::json& r, const LogContents& log) {
    ASSERT_GT(log.total, 0);
    EXPECT_EQ(r["decoded"], log.total);
    EXPECT_TRUE(r["invalid"].empty()) << r["invalid"];
    EXPECT_EQ(r["outOfOrder"], 0);
    for (const auto& [channel, n] : log.counts) {
      EXPECT_EQ(r["counts"].value(channel, -1), n) << channel;
      EXPECT_EQ(r["statistics"]["channelMessageCounts"].value(channel, -1), n) << channel;
      EXPECT_EQ(r["channels"][channel]["messageEncoding"], "json") << channel;
      EXPECT_EQ(r["channels"][channel]["schemaEncoding"], "jsonschema") << channel;
    }
    EXPECT_EQ(r["counts"].size(), log.counts.size());
    const auto& stats = r["statistics"];
    EXPECT_EQ(stats["messageCount"], log.total);
    EXPECT_EQ(stats["channelCount"], log.counts.size());
    EXPECT_EQ(stats["schemaCount"], log.counts.size());
    EXPECT_EQ(stats["messageStartTime"], std::to_string(log.min_time_ns));
    EXPECT_EQ(stats["messageEndTime"], std::to_string(log.max_time_ns));
    EXPECT_EQ(stats["chunkCount"], r["chunkIndexes"]);
    // Front to back with every CRC checked, as well.
    EXPECT_EQ(r["streamMessages"], log.total);
    EXPECT_TRUE(r["streamDone"].get<bool>());
    EXPECT_NE(r["dataEndCrc"], 0);
  }

  fs::path dir_;
};

TEST_F(Log2Mcap, EveryMessageOfTheLogReadsBackThroughTheIndexes) {
  const LogContents log = read_log(path("run.lcm"));
  for (const char* channel : {"RIGCTL_SAMPLE", "RIGCTL_COMMAND", "RIGCTL_CONTROLLER", "RIGCTL_STATE", "RIGCTL_TIMING"}) {
    EXPECT_GT(log.counts.count(channel), 0u) << channel << " missing from the run log";
  }
  std::string output;
  const auto r = convert_and_read(path("run.lcm"), path("run.mcap"), &output);
  EXPECT_EQ(output.find("warning"), std::string::npos) << output;
  expect_matches_log(r, log);
  EXPECT_GE(r["chunkIndexes"].get<int>(), 2) << "a run of this size fills more than one chunk";
  EXPECT_EQ(r["channels"]["RIGCTL_SAMPLE"]["schemaName"], "rigctl.Sample");
}

TEST_F(Log2Mcap, ATruncatedLogGivesWhatWasReadableAndAWarning) {
  // The log cut in the middle of an event, as a killed run or an
  // interrupted copy leaves it.
  const auto size = fs::file_size(path("run.lcm"));
  {
    std::ifstream in(path("run.lcm"), std::ios::binary);
    std::string head(size / 2 + 7, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    std::ofstream(path("cut.lcm"), std::ios::binary) << head;
  }
  const LogContents log = read_log(path("cut.lcm"));
  std::string output;
  const auto r = convert_and_read(path("cut.lcm"), path("cut.mcap"), &output);
  EXPECT_NE(output.find("warning: the log ends in"), std::string::npos) << output;
  expect_matches_log(r, log);
  EXPECT_LT(log.total, read_log(path("run.lcm")).total);
}

// A run of a test procedure: RIGCTL_PROCEDURE goes into the MCAP with the
// other channels, every message valid against its schema (rigctl.Procedure).
TEST_F(Log2Mcap, AProcedureRunsChannelGoesInWithTheOthers) {
  const auto run = run_command(kRigctl + " run " + kConfig + " --fast --procedure " + std::string(RIGCTL_SOURCE_DIR) +
                               "/config/quarter_car_procedure.yaml --duration 12 --log " + path("proc.lcm"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const LogContents log = read_log(path("proc.lcm"));
  ASSERT_GT(log.counts.count("RIGCTL_PROCEDURE"), 0u) << "no procedure messages in the run log";
  const auto r = convert_and_read(path("proc.lcm"), path("proc.mcap"));
  expect_matches_log(r, log);
  EXPECT_EQ(r["channels"]["RIGCTL_PROCEDURE"]["schemaName"], "rigctl.Procedure");

  // log2csv: the run file, and the procedure's messages beside it, one row each.
  const auto csv = run_command(kRigctl + " log2csv " + path("proc.lcm") + " " + path("proc.csv"));
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  std::ifstream in(path("proc.procedure.csv"));
  ASSERT_TRUE(in.good()) << csv.output;
  std::string header, line, last;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("t,tick,step,step_name,step_kind,phase,step_cycles,total_cycles,", 0), 0u) << header;
  int64_t rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, log.counts.at("RIGCTL_PROCEDURE"));
  EXPECT_NE(last.find("\"steps[1]\",sine,"), std::string::npos) << last;  // 12 s: still in the sine step
}

TEST_F(Log2Mcap, AFileThatIsNoLcmLogIsAnErrorNamingIt) {
  std::ofstream(path("notes.txt")) << "not a log\n";
  const auto r = run_command(kRigctl + " log2mcap " + path("notes.txt") + " " + path("out.mcap"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("notes.txt': not an LCM log"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.mcap")));
}

}  // namespace
