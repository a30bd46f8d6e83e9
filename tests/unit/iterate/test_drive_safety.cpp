// The drive safety check against the quarter car's limits from its config.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "config/config_reader.hpp"
#include "tools/iterate/drive_safety.hpp"

namespace rigctl {
namespace {

RigConfig quarter_car() { return load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml"); }

std::vector<double> sine(double op, double amplitude, double f_hz, double dt, double seconds) {
  std::vector<double> d;
  for (double t = 0; t < seconds; t += dt) d.push_back(op + amplitude * std::sin(2 * std::numbers::pi * f_hz * t));
  return d;
}

TEST(DriveSafety, LimitsComeFromTheConfigWithTheirSources) {
  const DriveLimits l = drive_limits(quarter_car());
  EXPECT_DOUBLE_EQ(l.position_min, 0.0);   // safety.setpoint_range, inside limits.x_r
  EXPECT_DOUBLE_EQ(l.position_max, 0.16);
  EXPECT_EQ(l.position_source, "safety.setpoint_range");
  EXPECT_NEAR(l.velocity_max, 0.7 * 0.6, 1e-12);  // x_r_rate; the 2 m/s x_r_jump is looser
  EXPECT_NE(l.velocity_source.find("x_r_rate"), std::string::npos);
  EXPECT_NEAR(l.effort_max, 0.8, 1e-12);
}

TEST(DriveSafety, ValveEffortFollowsTheOrificeLawBothWays) {
  const RigConfig c = quarter_car();
  // Retracting pushes on the small rod-side area against the load: more
  // effort for the same speed than extending.
  const double out = predicted_valve_effort(c, 0.1, 0.0), in = predicted_valve_effort(c, -0.1, 0.0);
  EXPECT_GT(in, out);
  EXPECT_NEAR(predicted_valve_effort(c, 0.2, 0.0), 2 * out, 1e-12);
  EXPECT_NEAR(out, 0.1 / 0.372, 0.01);  // Kv sqrt((A1 Ps - W) / (A1^3 + A2^3)) = 0.372 m/s per unit command
  EXPECT_NEAR(predicted_valve_effort(c, 0.0, -0.043), 0.043, 1e-12);
}

TEST(DriveSafety, AReachableDrivePasses) {
  const RigConfig c = quarter_car();
  const auto d = sine(0.08, 0.01, 1.0, c.loop.period_s, 3.0);
  const DriveVerdict v = check_drive(drive_peaks(c, d, 0.08, -0.043), drive_limits(c), 0.08);
  EXPECT_TRUE(v.ok) << v.reason;
  EXPECT_GT(v.fit_scale, 1.0);
}

TEST(DriveSafety, BeyondTheStrokeIsRefusedNamingTheStroke) {
  const RigConfig c = quarter_car();
  const auto d = sine(0.08, 0.1, 0.2, c.loop.period_s, 6.0);
  const DrivePeaks k = drive_peaks(c, d, 0.08, 0.0);
  EXPECT_NEAR(k.displacement, 0.1, 1e-4);
  const DriveVerdict v = check_drive(k, drive_limits(c), 0.08);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.reason.rfind("stroke: ", 0), 0u) << v.reason;
  EXPECT_NEAR(v.fit_scale, 0.8, 1e-3);  // 80 mm of room over a 100 mm swing
  std::vector<double> scaled = d;
  scale_drive(scaled, 0.08, v.fit_scale * 0.99);
  EXPECT_TRUE(check_drive(drive_peaks(c, scaled, 0.08, 0.0), drive_limits(c), 0.08).ok);
}

TEST(DriveSafety, BeyondTheValvesFlowIsRefusedNamingTheFlow) {
  const RigConfig c = quarter_car();
  const auto d = sine(0.08, 0.01, 8.0, c.loop.period_s, 2.0);  // 0.5 m/s peak
  const DriveVerdict v = check_drive(drive_peaks(c, d, 0.08, -0.043), drive_limits(c), 0.08);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.reason.rfind("flow: ", 0), 0u) << v.reason;  // the valve runs out before the rate detector's level
  EXPECT_LT(v.fit_scale, 0.5);
}

}  // namespace
}  // namespace rigctl
