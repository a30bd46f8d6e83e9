// The pneumatic servo's P + velocity + differential-pressure law (seed 002
// eq. 1, signs of docs/rig-models.md 2.6.1) and its transient-pressure variant.
#include <gtest/gtest.h>

#include <cmath>

#include "rt/control/pvp_controller.hpp"

using namespace rigctl;

namespace {
struct Tick {
  double u;
  ControllerTerms terms;
};

Tick step(PvpController& c, double setpoint, double angle, double dp) {
  Sample s;
  s.value[0] = angle;
  s.value[1] = dp;
  Command cmd;
  ControllerTerms t;
  c.update(setpoint, s, cmd, t);
  return {cmd.value[0], t};
}
}  // namespace

TEST(PvpController, EveryTermIsNegativeFeedback) {
  PvpConfig cfg;
  cfg.ke = 3.7;
  cfg.kp = 1.7e-5;
  cfg.kv = 0.3;
  cfg.velocity_filter_tau = 0.0;  // raw difference, so the test can predict it
  PvpController c(cfg);
  // Angle below demand: positive command (drive theta up).
  EXPECT_NEAR(step(c, 0.1, 0.0, 0.0).u, 0.37, 1e-12);
  // Positive differential pressure (torque pushing theta up): command reduced.
  const auto p = step(c, 0.1, 0.0, 1e5);
  EXPECT_NEAR(p.terms.term[1], -1.7, 1e-12);
  EXPECT_NEAR(p.u, 0.37 - 1.7, 1e-12);
  // Moving up at 0.4 rad/s (0.001 rad per 2.5 ms): command reduced by Kv omega.
  const auto v = step(c, 0.1, 0.001, 1e5);
  EXPECT_NEAR(v.terms.term[3], 0.4, 1e-9);
  EXPECT_NEAR(v.terms.term[2], -0.12, 1e-9);
}

TEST(PvpController, OutputSaturatesAtTheDacRange) {
  PvpConfig cfg;
  cfg.ke = 7.4;
  PvpController c(cfg);
  const auto t = step(c, 1.0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(t.u, 5.0);
  EXPECT_TRUE(t.terms.saturated);
  EXPECT_DOUBLE_EQ(t.terms.output_unsaturated, 7.4);
}

TEST(PvpController, TransientPressureFeedbackVanishesForASteadyPressure) {
  PvpConfig cfg;
  cfg.ke = 0.0;
  cfg.kp = 1.7e-5;
  cfg.transient_pressure = true;
  cfg.tau_f = 1.0;
  PvpController c(cfg);
  step(c, 0.0, 0.0, 0.0);
  // A pressure step of 1 bar: the high-passed term starts at ~Kp * 1 bar ...
  const auto first = step(c, 0.0, 0.0, 1e5);
  EXPECT_NEAR(first.terms.term[1], -1.7, 0.01);
  // ... and decays with tau_f: after 1 s to e^-1, after 5 s to ~0.
  double u = 0.0;
  for (int k = 1; k < 400; ++k) u = step(c, 0.0, 0.0, 1e5).u;
  EXPECT_NEAR(u, -1.7 * std::exp(-1.0), 0.02);
  for (int k = 0; k < 1600; ++k) u = step(c, 0.0, 0.0, 1e5).u;
  EXPECT_NEAR(u, 0.0, 0.02);
  // Plain pressure feedback keeps the full term at steady state.
  cfg.transient_pressure = false;
  PvpController plain(cfg);
  for (int k = 0; k < 2000; ++k) u = step(plain, 0.0, 0.0, 1e5).u;
  EXPECT_NEAR(u, -1.7, 1e-12);
}

TEST(PvpController, VelocityEstimateFollowsARampThroughItsFilter) {
  PvpConfig cfg;
  cfg.ke = 0.0;
  cfg.kv = 1.0;
  cfg.velocity_filter_tau = 0.01;
  PvpController c(cfg);
  double omega = 0.0;
  for (int k = 0; k < 200; ++k) omega = step(c, 0.0, 0.5 * k * 0.0025, 0.0).terms.term[3];
  EXPECT_NEAR(omega, 0.5, 1e-6);  // 0.5 s after the ramp began, the filter has settled
}
