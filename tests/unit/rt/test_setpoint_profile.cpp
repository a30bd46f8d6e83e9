#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "rt/control/setpoint_profile.hpp"

using namespace rigctl;

namespace {
LeadIn paper_lead_in() { return LeadIn{0.0, 0.08, 1.0, 0.02}; }
}  // namespace

TEST(Profile, RampStepsFollowsThePaperTest) {
  RampStepsProfile p(paper_lead_in(), {0.05, 0.0, -0.05}, 4.0);
  EXPECT_DOUBLE_EQ(p.at(0.5), 0.0);             // hold at home
  EXPECT_NEAR(p.at(3.0), 0.04, 1e-12);          // ramp at 20 mm/s after 1 s hold
  EXPECT_DOUBLE_EQ(p.step_time(0), 5.0);        // 1 s + 80 mm / 20 mm/s
  EXPECT_NEAR(p.at(5.0 + 1e-9), 0.13, 1e-12);   // first step: +50 mm
  EXPECT_NEAR(p.at(9.5), 0.08, 1e-12);
  EXPECT_NEAR(p.at(13.5), 0.03, 1e-12);
  EXPECT_DOUBLE_EQ(p.duration(), 17.0);
  EXPECT_NEAR(p.at(100.0), 0.03, 1e-12);        // holds the last step
}

TEST(Profile, FirstOrderFilterHasItsTimeConstant) {
  const double tau = 0.25, ts = 0.0025;
  FilteredProfile f(std::make_unique<RampStepsProfile>(LeadIn{0.0, 0.0, 0.0, 1.0}, std::vector<double>{0.05}, 10.0),
                    tau, ts);
  // The step is at t = 0 but the filter starts primed on the first value, so
  // prime with a zero first: build the step at t = 1 instead.
  FilteredProfile g(std::make_unique<RampStepsProfile>(LeadIn{0.0, 0.0, 1.0, 1.0}, std::vector<double>{0.05}, 10.0),
                    tau, ts);
  double y = 0.0;
  for (int k = 0; k <= 400 + 100; ++k) y = g.next(k * ts);  // up to t = 1.25 s: one tau after the step
  EXPECT_NEAR(y, 0.05 * (1.0 - std::exp(-1.0)), 0.05 * 0.02);
  EXPECT_NEAR(f.next(0.0), 0.05, 1e-15);  // primed: no transient from zero at start
}

TEST(Profile, SineAfterLeadIn) {
  SineProfile p(paper_lead_in(), 0.01, 2.0, 3.0);
  const double t0 = 5.0;
  EXPECT_NEAR(p.at(t0 + 0.125), 0.09, 1e-12);  // quarter period of 2 Hz
  EXPECT_NEAR(p.at(t0 + 0.375), 0.07, 1e-12);
  EXPECT_DOUBLE_EQ(p.duration(), t0 + 1.5);
}

TEST(Profile, CsvTableInterpolatesAndRejectsBadRows) {
  const auto dir = std::filesystem::temp_directory_path() / ("rigctl_profile_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto good = (dir / "good.csv").string();
  std::ofstream(good) << "# note: test\nt,x_ref\n0,0\n1,0.02\n3,0.02\n";
  const auto p = TableProfile::from_csv(good, "x_ref");
  EXPECT_NEAR(p.at(0.5), 0.01, 1e-15);
  EXPECT_NEAR(p.at(2.0), 0.02, 1e-15);
  EXPECT_NEAR(p.at(9.0), 0.02, 1e-15);
  EXPECT_DOUBLE_EQ(p.duration(), 3.0);

  const auto bad = (dir / "bad.csv").string();
  std::ofstream(bad) << "t,x_ref\n0,0\n1,abc\n";
  try {
    TableProfile::from_csv(bad, "x_ref");
    FAIL() << "text in a numeric cell must be an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("x_ref"), std::string::npos) << e.what();
  }
  const auto nocol = (dir / "nocol.csv").string();
  std::ofstream(nocol) << "t,y\n0,0\n1,1\n";
  EXPECT_THROW(TableProfile::from_csv(nocol, "x_ref"), std::runtime_error);
  const auto back = (dir / "back.csv").string();
  std::ofstream(back) << "t,x_ref\n0,0\n1,1\n0.5,1\n";
  EXPECT_THROW(TableProfile::from_csv(back, "x_ref"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(Profile, StartingFromTheMeasuredPositionKeepsTheTiming) {
  RampStepsProfile p(paper_lead_in(), {0.05}, 4.0);
  p.start_from(0.02);  // the rod stands at 20 mm, not at home
  EXPECT_DOUBLE_EQ(p.at(0.5), 0.02);           // holds where it stands: no jump
  EXPECT_NEAR(p.at(3.0), 0.02 + 0.03, 1e-12);  // halfway through the ramp at the same time
  EXPECT_DOUBLE_EQ(p.step_time(0), 5.0);       // steps keep their times
  FilteredProfile f(std::make_unique<RampStepsProfile>(paper_lead_in(), std::vector<double>{0.05}, 4.0), 0.25, 0.0025);
  f.start_from(-0.01);
  EXPECT_NEAR(f.next(0.0), -0.01, 1e-12) << "the filter starts at the measured position too";
}
