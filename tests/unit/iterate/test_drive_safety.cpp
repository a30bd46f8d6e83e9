// The drive safety check against the quarter car's limits from its config,
// on the motion predicted through the closed loop from the nominal model.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "config/config_reader.hpp"
#include "tools/identify/plant_linearisation.hpp"
#include "tools/iterate/drive_safety.hpp"

namespace rigctl {
namespace {

RigConfig quarter_car() {
  RigConfig c = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
  c.controller.pi.velocity_feedforward = 0.0;  // as rigctl iterate plays drives
  return c;
}

std::vector<double> sine(double op, double amplitude, double f_hz, double dt, double seconds) {
  std::vector<double> d;
  for (double t = 0; t < seconds; t += dt) {
    const double fade = std::min({1.0, t, seconds - t});  // 1 s in and out: no step at the ends
    d.push_back(op + fade * amplitude * std::sin(2 * std::numbers::pi * f_hz * t));
  }
  return d;
}

struct Rig {
  RigConfig config = quarter_car();
  LoopPaths paths = loop_paths_from_model(config, 0.08, model_frequencies(0.05, 40.0), "nominal model");
  double hold = linearise_quarter_car(config.quarter_car, 0.08, {"x_r"}).command;
  ValveLaw law = valve_law(config, hold);

  DrivePeaks peaks(const std::vector<double>& d, const PredictionCorrection& k = {}) const {
    return drive_peaks(d, 0.08, config.loop.period_s, predict_motion(paths, d, config.loop.period_s, hold, law, k));
  }
};

TEST(DriveSafety, LimitsComeFromTheConfigWithTheirSources) {
  const DriveLimits l = drive_limits(quarter_car());
  EXPECT_DOUBLE_EQ(l.position_min, 0.0);  // safety.setpoint_range, inside limits.x_r
  EXPECT_DOUBLE_EQ(l.position_max, 0.16);
  EXPECT_EQ(l.position_source, "safety.setpoint_range");
  EXPECT_NEAR(l.stroke_min, -0.012 + 0.03 * 0.184, 1e-12);  // limits.x_r less 3 % of its width
  EXPECT_NEAR(l.stroke_max, 0.172 - 0.03 * 0.184, 1e-12);
  EXPECT_EQ(l.stroke_source, "limits.x_r less 3 %");
  EXPECT_NEAR(l.velocity_max, 0.7 * 0.6, 1e-12);  // x_r_rate; the 2 m/s x_r_jump is looser
  EXPECT_NE(l.velocity_source.find("x_r_rate"), std::string::npos);
  EXPECT_NEAR(l.effort_max, 0.8, 1e-12);
}

// The rod follows the closed loop, not the drive: a drive at 8 Hz, above
// the loop's bandwidth, moves the rod by |T(8 Hz)| of its swing; the
// command is |T / G| of it about the hold.
TEST(DriveSafety, ThePredictionFollowsTheClosedLoop) {
  const Rig r;
  const double a = 0.004, f = 8.0;
  const DrivePeaks k = r.peaks(sine(0.08, a, f, r.config.loop.period_s, 6.0));
  const double w = 2 * std::numbers::pi * f;
  EXPECT_NEAR(k.velocity, a * w, 0.02 * a * w);  // the drive's own
  const double t = std::abs(r.paths.feedback.at(f)), u = std::abs(r.paths.command.at(f));
  EXPECT_LT(t, 0.9);
  EXPECT_NEAR(k.predicted.rod_velocity, t * a * w, 0.03 * t * a * w);
  EXPECT_NEAR(k.predicted.rod_max - 0.08, t * a, 0.03 * t * a);
  // The command by the orifice law at the rod's peak velocity, retracting (the weaker edge) ...
  const double v = t * a * w;
  EXPECT_NEAR(k.predicted.valve_effort, std::abs(r.law(-v)), 0.03 * std::abs(r.law(-v)));
  EXPECT_GT(std::abs(r.law(-v)), std::abs(r.law(v)));
  // ... and without a law, through the loop's FRF to the command.
  const PredictedMotion linear = predict_motion(r.paths, sine(0.08, a, f, r.config.loop.period_s, 6.0), r.config.loop.period_s, r.hold, {}, {});
  EXPECT_NEAR(linear.valve_effort, std::abs(r.hold) + u * a, 0.03 * (std::abs(r.hold) + u * a));
  // A measured ratio scales the next prediction.
  const DrivePeaks corrected = r.peaks(sine(0.08, a, f, r.config.loop.period_s, 6.0), PredictionCorrection{1.5, 1.25});
  EXPECT_NEAR(corrected.predicted.rod_velocity, 1.5 * k.predicted.rod_velocity, 1e-12);
  EXPECT_NEAR(corrected.predicted.valve_effort, 1.25 * k.predicted.valve_effort, 1e-12);
}

TEST(DriveSafety, TheValveLawFollowsTheOrificeBothWays) {
  const Rig r;
  const ValveLaw law = valve_law(r.config, 0.0);
  // Retracting pushes on the small rod-side area against the load: more
  // effort for the same speed than extending.
  EXPECT_GT(std::abs(law(-0.1)), law(0.1));
  EXPECT_NEAR(law(0.2), 2 * law(0.1), 1e-12);
  EXPECT_NEAR(law(0.1), 0.1 / 0.372, 0.01);  // Kv sqrt((A1 Ps - W) / (A1^3 + A2^3)) = 0.372 m/s per unit command
  EXPECT_NEAR(std::abs(law(-0.1)), 0.1 / 0.286, 0.01);
  EXPECT_NEAR(valve_law(r.config, -0.043)(0.0), -0.043, 1e-12);
}

TEST(DriveSafety, AReachableDrivePasses) {
  const Rig r;
  const DriveVerdict v = check_drive(r.peaks(sine(0.08, 0.01, 1.0, r.config.loop.period_s, 5.0)), drive_limits(r.config), 0.08);
  EXPECT_TRUE(v.ok) << v.reason;
  EXPECT_GT(v.fit_scale, 1.0);
}

TEST(DriveSafety, BeyondTheStrokeIsRefusedNamingTheStroke) {
  const Rig r;
  const auto d = sine(0.08, 0.1, 0.2, r.config.loop.period_s, 12.0);
  const DrivePeaks k = r.peaks(d);
  EXPECT_NEAR(k.displacement, 0.1, 2e-3);
  const DriveVerdict v = check_drive(k, drive_limits(r.config), 0.08);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.reason.rfind("stroke: ", 0), 0u) << v.reason;
  EXPECT_NEAR(v.fit_scale, 0.8, 0.02);  // 80 mm of room over a 100 mm swing
  std::vector<double> scaled = d;
  scale_drive(scaled, 0.08, v.fit_scale * 0.99);
  EXPECT_TRUE(check_drive(r.peaks(scaled), drive_limits(r.config), 0.08).ok);
}

TEST(DriveSafety, BeyondTheValvesFlowIsRefusedNamingTheFlow) {
  const Rig r;
  const auto d = sine(0.08, 0.032, 3.0, r.config.loop.period_s, 4.0);  // the rod at 0.6 m/s: twice its top speed
  const DrivePeaks k = r.peaks(d);
  const DriveVerdict v = check_drive(k, drive_limits(r.config), 0.08);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.reason.rfind("flow: ", 0), 0u) << v.reason;  // the valve runs out before the rate detector's level
  EXPECT_LT(v.fit_scale, 0.6);
}

}  // namespace
}  // namespace rigctl
