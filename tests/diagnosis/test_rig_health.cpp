// Rig health end to end, as a user runs it (docs/rig-health.md):
// `rigctl diagnose --catalog` enters a diagnosis linked to its run;
// `rigctl health analyse` calibrates a long run in windows into the catalog
// with the excitation check per window; `rigctl make-series` makes a rig
// whose seal wears block by block, and `rigctl health report` raises a
// leakage alarm against the truth the series wrote; a series without drift
// raises none.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "process.hpp"
#include "read_file.hpp"
#include "tools/catalog/catalog.hpp"
#include "tools/catalog/run_summary.hpp"

using rigctl::test::read_file;
using rigctl::test::run_command;
namespace fs = std::filesystem;
namespace cat = rigctl::catalog;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kSource = RIGCTL_SOURCE_DIR;

class RigHealth : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_health_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string db() const { return path("catalog.sqlite"); }

  // make-series into DIR, then every block analysed into the catalog as one window.
  nlohmann::json series(const std::string& dir, const std::string& drift, int blocks, int seed) {
    const auto made = run_command("cd " + kSource + " && " + kRigctl + " make-series --out " + path(dir) +
                                  " --blocks " + std::to_string(blocks) + " --seed " + std::to_string(seed) + " " + drift);
    EXPECT_EQ(made.exit_code, 0) << made.output;
    for (int i = 0; i < blocks; ++i) {
      char name[32];
      std::snprintf(name, sizeof name, "/block-%03d.csv", i);
      const auto a = run_command(kRigctl + " health analyse " + path(dir) + name + " --catalog " + db() +
                                 " --rig-name " + dir + " --window 20 --config " + kSource + "/config/quarter_car.yaml");
      EXPECT_EQ(a.exit_code, 0) << a.output;
    }
    return nlohmann::json::parse(read_file(path(dir) + "/series.json"));
  }

  nlohmann::json report(const std::string& rig) {
    const auto r = run_command(kRigctl + " health report --catalog " + db() + " --rig " + rig + " --json " +
                               path(rig + ".json") + " --html " + path(rig + ".html"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::printf("%s", r.output.c_str());
    return nlohmann::json::parse(read_file(path(rig + ".json")));
  }

  fs::path dir_;
};

}  // namespace

TEST_F(RigHealth, DiagnoseWritesItsResultIntoTheCatalogLinkedToTheRun) {
  const auto made = run_command("cd " + kSource + " && " + kRigctl +
                                " make-run --rig quarter_car --effect cross_port_leakage:strong --seed 2 --out " +
                                path("leak.csv"));
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const auto d = run_command(kRigctl + " diagnose --rig quarter_car --data " + path("leak.csv") + " --quiet --catalog " +
                             db() + " --rig-name bench-7");
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("catalog: diagnosis 1 of run 1"), std::string::npos) << d.output;
  cat::Catalog c(db());
  const auto run = c.run(1);
  ASSERT_TRUE(run);
  EXPECT_EQ(run->rig_name, "bench-7");
  EXPECT_EQ(run->entered_by, cat::EnteredBy::kAdd);
  const auto ds = c.diagnoses(1);
  ASSERT_EQ(ds.size(), 1u);
  EXPECT_EQ(ds[0].cause, "cross_port_leakage") << d.output;
  ASSERT_FALSE(ds[0].causes.empty());
  EXPECT_EQ(ds[0].causes[0].cause, "cross_port_leakage");
  EXPECT_GT(ds[0].causes[0].gain_pp, 0.0);
  bool r_l = false, c_il = false;
  for (const auto& p : ds[0].parameters) {
    if (p.role == "baseline" && p.name == "R_l") {
      r_l = true;
      EXPECT_EQ(p.stands_for, "cross_port_leakage");
      ASSERT_TRUE(p.value && p.sigma && p.nominal);
      EXPECT_GT(*p.sigma, 0.0);
    }
    if (p.role == "cross_port_leakage" && p.name == "C_il") c_il = p.value.has_value();
  }
  EXPECT_TRUE(r_l);
  EXPECT_TRUE(c_il);
  EXPECT_FALSE(ds[0].fits.empty());
  // `catalog show` lists it with the run.
  const auto show = run_command(kRigctl + " catalog show --catalog " + db() + " 1");
  EXPECT_NE(show.output.find("diagnosis 1 of"), std::string::npos) << show.output;
}

TEST_F(RigHealth, AnalyseCalibratesEachWindowAndSaysWhatItCouldNotDetermine) {
  // The shipped config's step test, 40 s: a ramp to mid-stroke, +-50 mm
  // steps, then holds; the windows after the steps hold the rod still.
  const std::string log = path("run.lcm");
  const auto run = run_command(kRigctl + " run " + kSource + "/config/quarter_car.yaml --fast --duration 40 --log " + log +
                               " --catalog " + db());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto a = run_command(kRigctl + " health analyse " + log + " --catalog " + db() + " --window 10");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  std::printf("%s", a.output.c_str());
  EXPECT_NE(a.output.find("health analyse: run 1, 4 windows"), std::string::npos) << a.output;
  cat::Catalog c(db());
  const auto ds = c.diagnoses(1);  // the run `rigctl run` entered
  ASSERT_EQ(ds.size(), 4u);
  int undetermined_somewhere = 0;
  for (std::size_t i = 0; i < ds.size(); ++i) {
    EXPECT_NEAR(ds[i].window_start_s, 10.0 * i, 0.05);
    EXPECT_EQ(ds[i].rig_name, "quarter_car");
    for (const auto& p : ds[i].parameters) {
      if (p.role != "baseline") continue;
      EXPECT_EQ(p.determined, p.value.has_value()) << p.name;
      if (!p.determined) {
        ++undetermined_somewhere;
        EXPECT_NE(ds[i].excitation.find(p.name), std::string::npos) << ds[i].excitation;
      }
    }
  }
  // A hold cannot determine what only motion shows.
  EXPECT_GT(undetermined_somewhere, 0) << a.output;
  // Again: every window is there already.
  const auto again = run_command(kRigctl + " health analyse " + log + " --catalog " + db() + " --window 10");
  EXPECT_NE(again.output.find("0 windows"), std::string::npos) << again.output;
}

TEST_F(RigHealth, AGrowingLeakIsAlarmedAsLeakageAndAStableRigIsNot) {
  // Ten blocks 10 h apart; the leakage conductance grows linearly to +50 %
  // at the last block, so +20 % is reached at block 4 (3.6 of 9).
  const auto truth = series("wearing", "--leakage-growth 0.5", 10, 3);
  const auto h = report("wearing");
  const nlohmann::json* r_l = nullptr;
  for (const auto& p : h["parameters"])
    if (p["name"] == "R_l") r_l = &p;
  ASSERT_NE(r_l, nullptr);
  ASSERT_FALSE((*r_l)["alarms"].empty()) << r_l->dump();
  const auto& alarm = (*r_l)["alarms"][0];
  EXPECT_EQ(alarm["stands_for"], "cross_port_leakage");
  EXPECT_EQ(alarm["direction"], -1);
  // Raised no later than two blocks after the 20 % rise was reached.
  const double reached = cat::utc_seconds(truth["blocks"][4]["start_utc"]);
  EXPECT_LE(alarm["raised_utc_s"].get<double>(), reached + 2 * 10 * 3600.0 + 1.0) << alarm.dump();
  EXPECT_NE(read_file(path("wearing.html")).find("cross_port_leakage: R_l fell"), std::string::npos);
  // Into the catalog, once.
  cat::Catalog c(db());
  EXPECT_FALSE(c.alarms("wearing").empty());
  const auto n = c.alarms("wearing").size();
  report("wearing");
  EXPECT_EQ(c.alarms("wearing").size(), n);

  // The same rig without wear: no alarm on any parameter.
  series("stable", "", 10, 3);
  const auto s = report("stable");
  for (const auto& p : s["parameters"]) EXPECT_TRUE(p["alarms"].empty()) << p.dump();
}
