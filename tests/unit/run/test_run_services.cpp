// RunServices, the owner of one `rigctl run`'s services: whatever way the
// run leaves, what was started is stopped and the catalog entry does not
// stay "running"; a refused option writes nothing. On the shipped
// quarter-car config, simulated (--fast), LCM in memory.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "config/config_reader.hpp"
#include "tools/catalog/catalog.hpp"
#include "tools/run/run_plan.hpp"
#include "tools/run/run_services.hpp"

namespace fs = std::filesystem;
using namespace rigctl;

namespace {

class RunServicesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_test_run_services_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    config_ = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml", "");
    options_.config_path = "config/quarter_car.yaml";
    options_.fast = true;
    options_.duration_s = 1.0;
    options_.log_path = (dir_ / "run.lcm").string();
    options_.catalog_path = (dir_ / "catalog.db").string();
  }
  void TearDown() override { fs::remove_all(dir_); }

  catalog::RunEntry entry() {
    catalog::Catalog c(options_.catalog_path);
    const auto run = c.run_by_log(options_.log_path);
    if (!run) throw std::runtime_error("the run is not in the catalog");
    return *run;
  }

  // The run's services built, started and the run entered in the catalog.
  std::unique_ptr<RunServices> started(RunPlan& plan) {
    auto services = std::make_unique<RunServices>(options_, plan);
    services->start();
    services->enter_in_catalog(out_);
    return services;
  }

  static std::size_t lines_of(const std::string& path) {
    std::ifstream in(path);
    std::size_t n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n;
  }

  fs::path dir_;
  RigConfig config_;
  RunOptions options_;
  std::ostringstream out_;
};

TEST_F(RunServicesTest, LeftRunningTheyStopAndTheCatalogEntryEndsFaulted) {
  RunPlan plan(config_, options_);
  {
    const auto services = started(plan);
    EXPECT_EQ(entry().end_reason, catalog::EndReason::kRunning);
  }  // an exception's way out: neither stop() nor fail() called
  const auto run = entry();
  EXPECT_EQ(run.end_reason, catalog::EndReason::kFaulted);
  EXPECT_EQ(run.end_detail, "run failed");
  // The event log was stopped and closed with its lines written.
  EXPECT_GT(lines_of(plan.records.events_path), 0u);
  EXPECT_TRUE(fs::exists(plan.records.log_path));
}

TEST_F(RunServicesTest, AFailedLoopEndsTheEntryFaultedWithItsReason) {
  RunPlan plan(config_, options_);
  const auto services = started(plan);
  services->fail("control loop failed");
  services->fail("again");  // nothing left to stop or finish
  const auto run = entry();
  EXPECT_EQ(run.end_reason, catalog::EndReason::kFaulted);
  EXPECT_EQ(run.end_detail, "control loop failed");
}

TEST_F(RunServicesTest, StopIsIdempotentAndTheEndIsTheCallers) {
  RunPlan plan(config_, options_);
  const auto services = started(plan);
  services->stop("control loop ended, closing the logs");
  services->stop("again");
  EXPECT_EQ(entry().end_reason, catalog::EndReason::kRunning);  // stop() leaves the entry to the caller
  services->finish_in_catalog(catalog::EndReason::kCompleted, "profile_finished");
  EXPECT_EQ(entry().end_reason, catalog::EndReason::kCompleted);
  EXPECT_GT(services->catalog_run_id(), 0);
}

TEST_F(RunServicesTest, AResumeWithoutAProcedureIsRefusedBeforeAnyFileIsWritten) {
  options_.resume_path = (dir_ / "run.lcm.recovery").string();
  RunPlan plan(config_, options_);
  try {
    RunServices services(options_, plan);
    FAIL() << "RunServices accepted --resume without --procedure";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "--resume continues a procedure: give its --procedure too");
  }
  EXPECT_FALSE(fs::exists(plan.records.log_path));
  EXPECT_FALSE(fs::exists(plan.records.events_path));
}

TEST_F(RunServicesTest, ARefusedOptionIsThrownByThePlan) {
  options_.duration_s = -1.0;
  EXPECT_THROW(RunPlan(config_, options_), std::runtime_error);
  EXPECT_FALSE(fs::exists(options_.log_path));
}

}  // namespace
