// `rigctl run` enters every run into the catalog at every end (completed,
// faulted, SIGINT); a kill -9 during a run leaves the file consistent with
// the run marked running, and `rigctl catalog repair` completes it from its
// log; `catalog add`, `list`, `query`, `show` on real runs (docs/rig-health.md 1).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "background_process.hpp"
#include "config_edit.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "tools/catalog/catalog.hpp"
#include "tools/catalog/run_summary.hpp"
#include "wait_until.hpp"

using rigctl::test::BackgroundProcess;
using rigctl::test::read_file;
using rigctl::test::run_command;
using rigctl::test::wait_until;
namespace fs = std::filesystem;
namespace cat = rigctl::catalog;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";

class CatalogRun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_catalog_run_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "logs");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string db() const { return path("catalog.sqlite"); }

  // The shipped config with a catalog: section naming this rig.
  std::string config_with_catalog() {
    std::string text = rigctl::test::without_overrun_stop(read_file(kConfig));
    text += "\ncatalog:\n  path: " + db() + "\n  rig_name: qc-test-rig\n";
    const std::string p = path("rig.yaml");
    std::ofstream(p) << text;
    return p;
  }

  fs::path dir_;
};

cat::RunEntry only_run(const std::string& db) {
  cat::Catalog c(db);
  const auto runs = c.runs({});
  EXPECT_EQ(runs.size(), 1u);
  return runs.empty() ? cat::RunEntry{} : *c.run(runs[0].id);
}

const cat::ChannelStats* channel(const cat::RunEntry& r, const std::string& name) {
  for (const auto& c : r.channels)
    if (c.channel == name) return &c;
  return nullptr;
}

}  // namespace

TEST_F(CatalogRun, ACompletedRunIsEnteredWithItsStatistics) {
  const auto run = run_command(kRigctl + " run " + config_with_catalog() + " --fast --duration 4 --log " +
                               path("logs/a.lcm") + " --csv " + path("a.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("catalog: run 1 in " + db() + " (completed)"), std::string::npos) << run.output;
  const auto r = only_run(db());
  EXPECT_EQ(r.rig_name, "qc-test-rig");
  EXPECT_EQ(r.rig_kind, "quarter_car");
  EXPECT_EQ(r.end_reason, cat::EndReason::kCompleted);
  EXPECT_EQ(r.entered_by, cat::EnteredBy::kRun);
  EXPECT_EQ(r.pid, 0);
  EXPECT_EQ(r.trips, 0);
  EXPECT_GE(r.duration_s, 3.99);  // the run's length, then the controlled stop
  EXPECT_LT(r.duration_s, 6.0);
  EXPECT_EQ(r.log_path, path("logs/a.lcm"));
  EXPECT_EQ(r.log_bytes, static_cast<int64_t>(fs::file_size(path("logs/a.lcm"))));
  // The hashes, against the coreutils' sha256sum.
  const auto log_sum = run_command("sha256sum " + path("logs/a.lcm"));
  EXPECT_EQ(log_sum.output.substr(0, 64), r.log_sha256);
  const auto config_sum = run_command("sha256sum " + path("rig.yaml"));
  EXPECT_EQ(config_sum.output.substr(0, 64), r.config_sha256);
  EXPECT_FALSE(r.revision.empty());
  EXPECT_NE(r.profile.find("ramp_steps"), std::string::npos) << r.profile;
  // The feedback channel's statistics agree with the run file of the same run
  // (the CSV holds the ticks with every message joined; the log all samples).
  const auto* x_r = channel(r, "x_r");
  ASSERT_NE(x_r, nullptr);
  EXPECT_GT(x_r->count, 1500);
  cat::Catalog scratch(path("scratch.sqlite"));
  const auto from_csv = scratch.run(scratch.add_run([&] {
    auto e = cat::summarise_record(path("a.csv"));
    e.rig_name = "x";
    return e;
  }()));
  const auto* x_r_csv = channel(*from_csv, "x_r");
  ASSERT_NE(x_r_csv, nullptr);
  EXPECT_NEAR(x_r->max, x_r_csv->max, 1e-6);
  EXPECT_NEAR(x_r->mean, x_r_csv->mean, 1e-4);
}

TEST_F(CatalogRun, AFaultedRunIsEnteredFaultedWithItsTrips) {
  const auto run = run_command(kRigctl + " run " + config_with_catalog() + " --fast --duration 7 --fault stuck@5:x_r --log " +
                               path("logs/f.lcm"));
  ASSERT_EQ(run.exit_code, 3) << run.output;
  const auto r = only_run(db());
  EXPECT_EQ(r.end_reason, cat::EndReason::kFaulted);
  EXPECT_NE(r.end_detail.find("sensor_stuck"), std::string::npos) << r.end_detail;
  EXPECT_GE(r.trips, 1);
  // Found by the filters.
  const auto faulted = run_command(kRigctl + " catalog list --catalog " + db() + " --end-reason faulted");
  EXPECT_EQ(faulted.exit_code, 0) << faulted.output;
  EXPECT_NE(faulted.output.find("1 run\n"), std::string::npos) << faulted.output;
  const auto none = run_command(kRigctl + " catalog list --catalog " + db() + " --end-reason completed");
  EXPECT_NE(none.output.find("0 runs\n"), std::string::npos) << none.output;
}

TEST_F(CatalogRun, SigintEndsTheRunInterruptedAndEntered) {
  BackgroundProcess proc({kRigctl, "run", config_with_catalog(), "--duration", "60", "--log", path("logs/s.lcm"),
                          "--no-realtime"},
                         path("out.txt"));
  ASSERT_TRUE(proc.wait_for("telemetry:", 60.0)) << proc.output();
  // The run is in the catalog while it runs.
  const auto running = [&] {
    if (!fs::exists(db())) return false;
    cat::Catalog c(db());
    const auto runs = c.runs({});
    return runs.size() == 1 && runs[0].end_reason == cat::EndReason::kRunning;
  };
  ASSERT_TRUE(wait_until(running, 60.0));
  // Telemetry on the disk, so the entry has statistics to take.
  ASSERT_TRUE(wait_until([&] { return fs::exists(path("logs/s.lcm")) && fs::file_size(path("logs/s.lcm")) > 100000; }, 60.0));
  ASSERT_GT(proc.pid(), 0) << proc.output();
  ASSERT_EQ(::kill(proc.pid(), SIGINT), 0);
  EXPECT_EQ(proc.wait(), 0) << proc.output();
  const auto r = only_run(db());
  EXPECT_EQ(r.end_reason, cat::EndReason::kInterrupted) << proc.output();
  EXPECT_EQ(r.pid, 0);
  EXPECT_GT(r.samples, 0);
}

TEST_F(CatalogRun, KillNineLeavesTheCatalogConsistentAndRepairEntersTheRun) {
  BackgroundProcess proc({kRigctl, "run", config_with_catalog(), "--duration", "60", "--log", path("logs/k.lcm"),
                          "--no-realtime"},
                         path("out.txt"));
  ASSERT_TRUE(proc.wait_for("telemetry:", 60.0)) << proc.output();
  // Over a second of telemetry on the disk, so the repaired entry has a log to read.
  ASSERT_TRUE(wait_until([&] { return fs::exists(path("logs/k.lcm")) && fs::file_size(path("logs/k.lcm")) > 200000; }, 60.0));
  ASSERT_GT(proc.pid(), 0) << proc.output();
  ASSERT_EQ(::kill(proc.pid(), SIGKILL), 0);
  proc.wait();

  // SQLite's own check of the file, then the run as the kill left it.
  {
    sqlite3* h = nullptr;
    ASSERT_EQ(sqlite3_open(db().c_str(), &h), SQLITE_OK);
    sqlite3_stmt* s = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &s, nullptr), SQLITE_OK);
    ASSERT_EQ(sqlite3_step(s), SQLITE_ROW);
    EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)), "ok");
    sqlite3_finalize(s);
    sqlite3_close(h);
  }
  const auto killed = only_run(db());
  EXPECT_EQ(killed.end_reason, cat::EndReason::kRunning);
  EXPECT_GT(killed.pid, 0);

  // A second log in the folder that no catalog knows (a run without one).
  const auto other = run_command(kRigctl + " run " + kConfig + " --fast --duration 2 --log " + path("logs/other.lcm"));
  ASSERT_EQ(other.exit_code, 0) << other.output;

  const auto repair = run_command(kRigctl + " catalog repair --config " + path("rig.yaml") + " --log-dir " + path("logs"));
  ASSERT_EQ(repair.exit_code, 0) << repair.output;
  EXPECT_NE(repair.output.find("repair: run 1 completed from " + path("logs/k.lcm") + " (killed"), std::string::npos)
      << repair.output;
  EXPECT_NE(repair.output.find(path("logs/other.lcm") + " entered as run 2 (completed"), std::string::npos) << repair.output;
  cat::Catalog c(db());
  const auto r = *c.run(1);
  EXPECT_EQ(r.end_reason, cat::EndReason::kKilled);
  EXPECT_EQ(r.entered_by, cat::EnteredBy::kRepair);
  EXPECT_GT(r.duration_s, 0.5);
  EXPECT_GT(r.samples, 200);
  EXPECT_EQ(r.log_bytes, static_cast<int64_t>(fs::file_size(path("logs/k.lcm"))));
  ASSERT_NE(channel(r, "x_r"), nullptr);
  EXPECT_EQ(c.run(2)->rig_name, "qc-test-rig");  // the config's name for the unknown log
  // A second repair finds nothing to do.
  const auto again = run_command(kRigctl + " catalog repair --config " + path("rig.yaml") + " --log-dir " + path("logs"));
  EXPECT_EQ(again.output.find("repair:"), std::string::npos) << again.output;
}

TEST_F(CatalogRun, AddQueryAndShowOlderRecords) {
  ASSERT_EQ(run_command(kRigctl + " run " + kConfig + " --fast --duration 3 --log " + path("logs/old.lcm") + " --csv " +
                        path("old.csv")).exit_code, 0);
  const auto add = run_command(kRigctl + " catalog add --catalog " + db() + " --rig-name bench-3 " + path("logs/old.lcm") +
                               " " + path("old.csv"));
  ASSERT_EQ(add.exit_code, 0) << add.output;
  EXPECT_NE(add.output.find("entered as run 1 (bench-3, completed"), std::string::npos) << add.output;
  EXPECT_NE(add.output.find("entered as run 2 (bench-3, unknown"), std::string::npos) << add.output;
  const auto twice = run_command(kRigctl + " catalog add --catalog " + db() + " " + path("old.csv"));
  EXPECT_EQ(twice.exit_code, 1);
  EXPECT_NE(twice.output.find("already entered as run 2"), std::string::npos) << twice.output;

  const auto q = run_command(kRigctl + " catalog query --catalog " + db() + " --where 'x_r.max>0.01' --rig bench-3 2>/dev/null");
  ASSERT_EQ(q.exit_code, 0) << q.output;
  const auto j = nlohmann::json::parse(q.output);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_GT(j[0]["channels"]["x_r"]["max"].get<double>(), 0.01);
  const auto none = run_command(kRigctl + " catalog query --catalog " + db() + " --where 'x_r.max>10'");
  EXPECT_EQ(nlohmann::json::parse(none.output).size(), 0u);
  const auto bad = run_command(kRigctl + " catalog list --catalog " + db() + " --where 'x_r.peak>1'");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("unknown statistic 'peak' (known: min, max, mean, std, rms)"), std::string::npos) << bad.output;

  const auto show = run_command(kRigctl + " catalog show --catalog " + db() + " 1");
  ASSERT_EQ(show.exit_code, 0) << show.output;
  EXPECT_NE(show.output.find("run 1: bench-3 (quarter_car)"), std::string::npos) << show.output;
  EXPECT_NE(show.output.find("  x_r "), std::string::npos) << show.output;
  const auto missing = run_command(kRigctl + " catalog show --catalog " + db() + " 9");
  EXPECT_EQ(missing.exit_code, 2);
}
