// The run catalog on a real SQLite file (tools/catalog): entries, filters,
// the schema's migration from its first version, channel statistics of run
// files checked against an independent computation, and no half entry.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <filesystem>
#include <fstream>
#include <random>

#include "tools/catalog/catalog.hpp"
#include "tools/catalog/run_summary.hpp"
#include "tools/catalog/schema.hpp"

namespace fs = std::filesystem;
using namespace rigctl::catalog;

namespace {

class CatalogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigctl_catalog_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

RunEntry entry(const std::string& rig, const std::string& start, EndReason end, const std::string& log, double x_max) {
  RunEntry r;
  r.rig_kind = "quarter_car";
  r.rig_name = rig;
  r.start_utc = start;
  r.duration_s = 10.0;
  r.end_reason = end;
  r.log_path = log;
  r.entered_by = EnteredBy::kAdd;
  r.channels.push_back({"x_r", "m", 100, -x_max, x_max, 0.0, x_max / 2, x_max / 2});
  r.channels.push_back({"p1", "Pa", 100, 1e6, 9e6, 5e6, 1e6, 5.1e6});
  return r;
}

// Straight SQL on the file, not through the catalog's own code.
int64_t count_rows(const std::string& db_path, const std::string& table) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, ("SELECT count(*) FROM " + table).c_str(), -1, &s, nullptr), SQLITE_OK);
  EXPECT_EQ(sqlite3_step(s), SQLITE_ROW);
  const int64_t n = sqlite3_column_int64(s, 0);
  sqlite3_finalize(s);
  sqlite3_close(db);
  return n;
}

}  // namespace

TEST_F(CatalogTest, CreatedOnFirstUseAtTheCurrentSchemaVersion) {
  const std::string db = path("sub/dir/catalog.sqlite");
  { Catalog c(db); }
  ASSERT_TRUE(fs::exists(db));
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  sqlite3_stmt* s = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(h, "PRAGMA user_version", -1, &s, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(s, 0), kSchemaVersion);
  sqlite3_finalize(s);
  sqlite3_close(h);
}

TEST_F(CatalogTest, FiltersByRigDateEndReasonAndChannelStatistic) {
  Catalog c(path("catalog.sqlite"));
  c.add_run(entry("rig-a", "2026-11-01T08:00:00.000000Z", EndReason::kCompleted, "/logs/a1.lcm", 0.05));
  c.add_run(entry("rig-a", "2026-11-02T08:00:00.000000Z", EndReason::kFaulted, "/logs/a2.lcm", 0.09));
  c.add_run(entry("rig-b", "2026-11-03T08:00:00.000000Z", EndReason::kCompleted, "/logs/b1.lcm", 0.02));

  RunFilter f;
  EXPECT_EQ(c.runs(f).size(), 3u);
  f.rig = "rig-a";
  EXPECT_EQ(c.runs(f).size(), 2u);
  f.rig = "quarter_car";  // the kind matches too
  EXPECT_EQ(c.runs(f).size(), 3u);
  f = {};
  f.since = "2026-11-02";
  EXPECT_EQ(c.runs(f).size(), 2u);
  f.until = "2026-11-03";
  ASSERT_EQ(c.runs(f).size(), 1u);
  EXPECT_EQ(c.runs(f)[0].log_path, "/logs/a2.lcm");
  f = {};
  f.end_reason = EndReason::kFaulted;
  ASSERT_EQ(c.runs(f).size(), 1u);
  EXPECT_EQ(c.runs(f)[0].rig_name, "rig-a");
  f = {};
  f.channels.push_back(parse_channel_condition("x_r.max>0.04"));
  EXPECT_EQ(c.runs(f).size(), 2u);
  f.channels.push_back(parse_channel_condition("x_r.max<0.06"));
  ASSERT_EQ(c.runs(f).size(), 1u);
  EXPECT_EQ(c.runs(f)[0].log_path, "/logs/a1.lcm");
  f = {};
  f.channels.push_back(parse_channel_condition("nope.mean>0"));
  EXPECT_TRUE(c.runs(f).empty());
}

TEST_F(CatalogTest, ABadConditionNamesItsText) {
  EXPECT_THROW(parse_channel_condition("x_r>0.05"), CatalogError);
  try {
    parse_channel_condition("x_r.peak>0.05");
    FAIL();
  } catch (const CatalogError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown statistic 'peak'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_channel_condition("x_r.max>abc"), CatalogError);
}

TEST_F(CatalogTest, ALogIsEnteredOnceAndAFailedEntryLeavesNothing) {
  const std::string db = path("catalog.sqlite");
  Catalog c(db);
  const int64_t id = c.add_run(entry("rig-a", "2026-11-01T08:00:00Z", EndReason::kCompleted, "/logs/a1.lcm", 0.05));
  try {
    c.add_run(entry("rig-a", "2026-11-01T09:00:00Z", EndReason::kCompleted, "/logs/a1.lcm", 0.05));
    FAIL() << "entered twice";
  } catch (const CatalogError& e) {
    EXPECT_NE(std::string(e.what()).find("already entered as run " + std::to_string(id)), std::string::npos) << e.what();
  }
  // A channel twice violates the statistics' key after the run row went in:
  // the transaction takes the run row back out.
  RunEntry bad = entry("rig-a", "2026-11-01T10:00:00Z", EndReason::kCompleted, "/logs/a3.lcm", 0.05);
  bad.channels.push_back(bad.channels.front());
  EXPECT_THROW(c.add_run(bad), CatalogError);
  EXPECT_EQ(count_rows(db, "runs"), 1);
  EXPECT_EQ(count_rows(db, "channel_stats"), 2);
}

TEST_F(CatalogTest, BeginAndFinishReplaceTheRunningEntry) {
  Catalog c(path("catalog.sqlite"));
  RunEntry r = entry("rig-a", "2026-11-01T08:00:00Z", EndReason::kCompleted, "/logs/a1.lcm", 0.05);
  r.channels.clear();
  r.pid = 4242;
  const int64_t id = c.begin_run(r);
  EXPECT_EQ(c.run(id)->end_reason, EndReason::kRunning);
  EXPECT_EQ(c.run(id)->pid, 4242);
  r = entry("rig-a", "2026-11-01T08:00:00Z", EndReason::kFaulted, "/logs/a1.lcm", 0.07);
  r.trips = 2;
  c.finish_run(id, r);
  const auto done = c.run(id);
  EXPECT_EQ(done->end_reason, EndReason::kFaulted);
  EXPECT_EQ(done->trips, 2);
  ASSERT_EQ(done->channels.size(), 2u);
  EXPECT_DOUBLE_EQ(done->channels[0].max, 0.07);
}

// A file as the first version wrote it (the DDL copied here, not taken from
// the code) is migrated with its runs kept, and takes the new tables.
TEST_F(CatalogTest, MigratesAVersionOneFileKeepingItsRuns) {
  const std::string db = path("v1.sqlite");
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  const char* v1 = R"sql(
    CREATE TABLE runs (id INTEGER PRIMARY KEY, rig_kind TEXT NOT NULL, rig_name TEXT NOT NULL,
      config_path TEXT NOT NULL DEFAULT '', config_sha256 TEXT NOT NULL DEFAULT '', revision TEXT NOT NULL DEFAULT '',
      start_utc TEXT NOT NULL, duration_s REAL NOT NULL DEFAULT 0, profile TEXT NOT NULL DEFAULT '',
      end_reason TEXT NOT NULL, end_detail TEXT NOT NULL DEFAULT '', trips INTEGER NOT NULL DEFAULT 0,
      samples INTEGER NOT NULL DEFAULT 0, log_path TEXT NOT NULL UNIQUE, log_bytes INTEGER NOT NULL DEFAULT 0,
      log_sha256 TEXT NOT NULL DEFAULT '', entered_by TEXT NOT NULL);
    CREATE INDEX runs_by_rig_start ON runs(rig_name, start_utc);
    CREATE TABLE channel_stats (run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE, channel TEXT NOT NULL,
      unit TEXT NOT NULL DEFAULT '', count INTEGER NOT NULL, min REAL, max REAL, mean REAL, std REAL, rms REAL,
      PRIMARY KEY (run_id, channel));
    INSERT INTO runs (rig_kind, rig_name, start_utc, duration_s, end_reason, trips, log_path, entered_by)
      VALUES ('quarter_car', 'rig-old', '2025-01-02T03:04:05Z', 12.5, 'faulted', 3, '/old/run.lcm', 'run');
    INSERT INTO channel_stats VALUES (1, 'x_r', 'm', 5000, -0.05, 0.05, 0.0, 0.03, 0.03);
    PRAGMA user_version = 1;
  )sql";
  ASSERT_EQ(sqlite3_exec(h, v1, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(h);
  sqlite3_close(h);

  Catalog c(db);
  const auto old = c.run(1);
  ASSERT_TRUE(old);
  EXPECT_EQ(old->rig_name, "rig-old");
  EXPECT_EQ(old->end_reason, EndReason::kFaulted);
  EXPECT_EQ(old->trips, 3);
  EXPECT_EQ(old->pid, 0);  // the new column's default
  ASSERT_EQ(old->channels.size(), 1u);
  EXPECT_DOUBLE_EQ(old->channels[0].std, 0.03);
  // The version 2 tables work on the migrated file.
  DiagnosisEntry d;
  d.run_id = 1;
  d.rig_name = "rig-old";
  d.parameters.push_back({"baseline", "R_l", "Pa s/m^3", 1e12, 0.9e12, 0.05e12, 0.1, true, "cross_port_leakage"});
  const int64_t did = c.add_diagnosis(d);
  ASSERT_EQ(c.diagnoses(1).size(), 1u);
  EXPECT_EQ(c.diagnoses(1)[0].id, did);
  EXPECT_EQ(c.diagnoses(1)[0].parameters[0].stands_for, "cross_port_leakage");
  EXPECT_EQ(count_rows(db, "alarms"), 0);
}

TEST_F(CatalogTest, RefusesAFileOfANewerSchema) {
  const std::string db = path("new.sqlite");
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(h, ("PRAGMA user_version = " + std::to_string(kSchemaVersion + 1)).c_str(), nullptr, nullptr,
                         nullptr),
            SQLITE_OK);
  sqlite3_close(h);
  try {
    Catalog c(db);
    FAIL();
  } catch (const CatalogError& e) {
    EXPECT_NE(std::string(e.what()).find("newer than this rigctl"), std::string::npos) << e.what();
  }
}

// The statistics of a run file, against a two-pass computation here over
// values this test drew (a large offset: the one-pass update must not cancel).
TEST_F(CatalogTest, RunFileStatisticsMatchATwoPassComputation) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> a, b;
  std::ofstream f(path("run.csv"));
  f << "# rig: quarter_car\n# start_utc: 2026-11-05T10:00:00Z\nt,a,b\n";
  for (int i = 0; i < 5000; ++i) {
    a.push_back(1e6 + 0.01 * noise(rng));
    b.push_back(std::sin(0.01 * i) + 0.1 * noise(rng));
    f << i * 0.0025 << "," << std::setprecision(17) << a.back() << "," << b.back() << "\n";
  }
  f.close();
  const RunEntry r = summarise_record(path("run.csv"));
  EXPECT_EQ(r.rig_kind, "quarter_car");
  EXPECT_EQ(r.start_utc, "2026-11-05T10:00:00Z");
  EXPECT_EQ(r.samples, 5000);
  EXPECT_NEAR(r.duration_s, 4999 * 0.0025, 1e-9);
  EXPECT_EQ(r.end_reason, EndReason::kUnknown);
  EXPECT_EQ(r.log_sha256.size(), 64u);
  ASSERT_EQ(r.channels.size(), 2u);
  const std::vector<double>* cols[] = {&a, &b};
  for (int k = 0; k < 2; ++k) {
    const auto& v = *cols[k];
    double mean = 0, sq = 0, var = 0;
    for (double x : v) mean += x, sq += x * x;
    mean /= v.size();
    for (double x : v) var += (x - mean) * (x - mean);
    const auto& s = r.channels[k];
    EXPECT_EQ(s.count, 5000);
    EXPECT_NEAR(s.mean, mean, 1e-9 * std::abs(mean) + 1e-12);
    EXPECT_NEAR(s.std, std::sqrt(var / (v.size() - 1)), 1e-6 * std::sqrt(var / (v.size() - 1)));
    EXPECT_NEAR(s.rms, std::sqrt(sq / v.size()), 1e-9 * std::sqrt(sq / v.size()));
    EXPECT_DOUBLE_EQ(s.min, *std::min_element(v.begin(), v.end()));
    EXPECT_DOUBLE_EQ(s.max, *std::max_element(v.begin(), v.end()));
  }
}

TEST_F(CatalogTest, Sha256OfAKnownText) {
  std::ofstream(path("abc")) << "abc";
  // FIPS 180-2's example.
  EXPECT_EQ(file_sha256(path("abc")), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST_F(CatalogTest, UtcTextRoundTrips) {
  EXPECT_EQ(utc_text(1'700'000'000'250'000), "2023-11-14T22:13:20.250000Z");
  EXPECT_DOUBLE_EQ(utc_seconds("2023-11-14T22:13:20.250000Z"), 1'700'000'000.25);
  EXPECT_DOUBLE_EQ(utc_seconds("2023-11-14"), 1'699'920'000.0);
  EXPECT_THROW(utc_seconds("yesterday"), std::invalid_argument);
}
