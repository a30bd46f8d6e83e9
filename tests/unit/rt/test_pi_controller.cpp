// The discrete PI law with output saturation and conditional-integration
// anti-windup.
#include <gtest/gtest.h>

#include "rt/control/pi_controller.hpp"

using namespace rigctl;

namespace {
struct Step {
  double u;
  ControllerTerms terms;
};

Step run_once(PiController& pi, double setpoint, double measured) {
  Sample s;
  s.value[0] = measured;
  Command c;
  ControllerTerms t;
  pi.update(setpoint, s, c, t);
  return {c.value[0], t};
}

// A pure integrator plant y' = g u: the textbook case where windup shows.
double overshoot_after_saturation(AntiWindup mode) {
  PiConfig cfg;
  cfg.kp = 80.0;  // the rig's gains; with this plant the linear loop is overdamped (zeta 1.15)
  cfg.ki = 60.0;
  cfg.period_s = 0.0025;
  cfg.output_limit = 1.0;
  cfg.anti_windup = mode;
  PiController pi(cfg);
  const double gain = 0.05;  // [m/s] per unit output: a large step saturates for ~1.5 s
  double y = 0.0, peak = 0.0;
  const double target = 0.08;
  for (int k = 0; k < 8000; ++k) {
    const double u = run_once(pi, target, y).u;
    y += gain * u * cfg.period_s;
    peak = std::max(peak, y);
  }
  EXPECT_NEAR(y, target, 1e-4) << "must still settle";
  return peak - target;
}
}  // namespace

TEST(PiController, ProportionalAndIntegralParts) {
  PiConfig cfg;
  cfg.kp = 80.0;
  cfg.ki = 60.0;
  cfg.period_s = 0.0025;
  PiController pi(cfg);
  const auto a = run_once(pi, 0.010, 0.0);  // e = 10 mm
  EXPECT_DOUBLE_EQ(a.terms.error, 0.010);
  EXPECT_DOUBLE_EQ(a.terms.term[0], 0.8);
  EXPECT_DOUBLE_EQ(a.terms.term[1], 60.0 * 0.0025 * 0.010);
  EXPECT_DOUBLE_EQ(a.u, 0.8 + 60.0 * 0.0025 * 0.010);
  EXPECT_FALSE(a.terms.saturated);
  // The integrator accumulates (it is an integrator, unlike the paper's eq. 9).
  const auto b = run_once(pi, 0.010, 0.0);
  EXPECT_DOUBLE_EQ(b.terms.term[1], 2 * 60.0 * 0.0025 * 0.010);
  // And removes a constant offset: zero error keeps the integral output.
  const auto c = run_once(pi, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(c.u, b.terms.term[1]);
}

TEST(PiController, OutputSaturatesAndIntegratorIsHeld) {
  PiConfig cfg;
  cfg.kp = 80.0;
  cfg.ki = 60.0;
  PiController pi(cfg);
  for (int k = 0; k < 1000; ++k) {
    const auto s = run_once(pi, 0.05, 0.0);  // e = 50 mm: P part alone is 4
    EXPECT_DOUBLE_EQ(s.u, 1.0);
    EXPECT_TRUE(s.terms.saturated);
    EXPECT_TRUE(s.terms.integrator_held);
  }
  EXPECT_DOUBLE_EQ(pi.integrator(), 0.0);
  // Error reversing while still saturated low: integration resumes at once.
  const auto r = run_once(pi, -0.05, 0.0);
  EXPECT_DOUBLE_EQ(r.u, -1.0);
  EXPECT_TRUE(r.terms.integrator_held);
  const auto back = run_once(pi, 0.001, 0.0);
  EXPECT_FALSE(back.terms.integrator_held);
  EXPECT_GT(pi.integrator(), 0.0);
}

TEST(PiController, AntiWindupCutsOvershootAfterSaturation) {
  const double with = overshoot_after_saturation(AntiWindup::kConditional);
  const double without = overshoot_after_saturation(AntiWindup::kNone);
  EXPECT_LT(with, 0.002) << "conditional integration: little overshoot";
  EXPECT_GT(without, 3.0 * with + 0.005) << "a wound-up integrator overshoots far more";
}

// A tick whose sample says the valve is not following: the command is
// still computed and recorded, the error is not integrated; once it follows
// again the integrator goes on from where it was, with nothing wound up.
TEST(PiController, IntegratorIsHeldWhileTheOutputIsNotFollowing) {
  PiConfig cfg;
  cfg.kp = 80.0;
  cfg.ki = 60.0;
  cfg.period_s = 0.0025;
  cfg.output_index = 1;
  PiController pi(cfg);
  Sample s;
  s.value[0] = 0.0;
  Command c;
  ControllerTerms t;
  pi.update(0.005, s, c, t);  // following: one step of integration
  const double before = pi.integrator();
  EXPECT_GT(before, 0.0);
  s.outputs_not_following = 1U << 1;
  for (int k = 0; k < 200; ++k) {  // half a second of a valve in HOLD with a 5 mm error
    pi.update(0.005, s, c, t);
    EXPECT_TRUE(t.integrator_held);
    EXPECT_DOUBLE_EQ(t.term[1], before);
    EXPECT_DOUBLE_EQ(c.value[1], 80.0 * 0.005 + before);  // the command is still computed
    EXPECT_DOUBLE_EQ(t.output, c.value[1]);
  }
  EXPECT_DOUBLE_EQ(pi.integrator(), before);
  // Another output not following does not concern this controller.
  s.outputs_not_following = 1U << 0;
  pi.update(0.005, s, c, t);
  EXPECT_FALSE(t.integrator_held);
  EXPECT_DOUBLE_EQ(pi.integrator(), before + 60.0 * 0.0025 * 0.005);
}

// The integrator plant of the test above following a 0.05 m/s ramp: the PI
// alone lags by up to speed / (kp g) until its integrator has caught up
// (the loop is type 2, so only in the transient); with the feedforward 1 / g
// the valve opens for the ramp's speed at once and the largest lag is the
// one-period delay of the discrete loop. Returns the largest lag.
double ramp_lag(double velocity_feedforward) {
  PiConfig cfg;
  cfg.kp = 80.0;
  cfg.ki = 60.0;
  cfg.period_s = 0.0025;
  cfg.velocity_feedforward = velocity_feedforward;
  PiController pi(cfg);
  const double gain = 0.5, speed = 0.05;  // [m/s per unit output], [m/s]
  double y = 0.0, lag = 0.0;
  for (int k = 0; k < 800; ++k) {  // 2 s of ramp
    const double r = speed * k * cfg.period_s;
    lag = std::max(lag, r - y);
    y += gain * run_once(pi, r, y).u * cfg.period_s;
  }
  return lag;
}

TEST(PiController, VelocityFeedforwardRemovesTheLagOfARamp) {
  const double without = ramp_lag(0.0), with = ramp_lag(1.0 / 0.5);
  EXPECT_GT(without, 0.05 * 0.0025 * 5.0) << "the PI alone lags by many periods of motion";
  EXPECT_LE(with, 0.05 * 0.0025 * 1.01) << "at most one period's motion";
  EXPECT_LT(with, 0.15 * without);
}

TEST(PiController, FeedforwardIsTheDemandRateAndNoneOnTheFirstTick) {
  PiConfig cfg;
  cfg.kp = 0.0;
  cfg.ki = 0.0;
  cfg.period_s = 0.0025;
  cfg.velocity_feedforward = 2.0;  // [s/m]
  PiController pi(cfg);
  EXPECT_EQ(pi.term_names(), (std::vector<std::string>{"p", "i", "ff"}));
  // A run that starts where the rod stands starts without a kick.
  EXPECT_DOUBLE_EQ(run_once(pi, 0.080, 0.080).u, 0.0);
  const auto a = run_once(pi, 0.080 + 0.0001, 0.080);  // 0.04 m/s
  EXPECT_NEAR(a.terms.term[2], 2.0 * 0.04, 1e-12);
  EXPECT_NEAR(a.u, 2.0 * 0.04, 1e-12);
  pi.reset();
  EXPECT_DOUBLE_EQ(run_once(pi, 0.0, 0.0).u, 0.0) << "reset forgets the previous demand";
  // Without it the controller publishes only its two terms (run files keep their columns).
  cfg.velocity_feedforward = 0.0;
  EXPECT_EQ(PiController(cfg).term_names(), (std::vector<std::string>{"p", "i"}));
  cfg.velocity_feedforward = -1.0;
  EXPECT_THROW(PiController{cfg}, std::invalid_argument);
}
