// Open-loop checks of the rotary pneumatic rig's bladder hysteresis and
// Coulomb brake, alone and inside the plant, against hand calculations from
// docs/rig-models.md section 2 and seed 002 (Fig. 2b), not against numbers
// read back from the implementation.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <numbers>
#include <vector>

#include "plant/pneumatic_rotary/bladder_hysteresis.hpp"
#include "plant/pneumatic_rotary/coulomb_friction.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_plant.hpp"
#include "allocation_counter.hpp"
#include "pneumatic_plant_stepping.hpp"

namespace rigctl {
namespace {

using namespace pneumatic_test;

// -------------------------------------------------------------- hysteresis

BladderHysteresisLevels nominal_levels() {
  return bladder_hysteresis_levels(BladderHysteresisParams{}, 75.0);
}

TEST(BladderHysteresis, LevelsFromTheNominalParameters) {
  const auto l = nominal_levels();
  // +-2 % of 75 N m = +-1.5 N m (the paper's Fig. 2a); half of the 3 N m
  // swing taken stepwise, the other half over 0.035 rad.
  EXPECT_NEAR(l.half_width, 1.5, 1e-12);
  EXPECT_NEAR(l.step, 0.75, 1e-12);
  EXPECT_NEAR(l.elastic_limit, 0.75, 1e-12);
  EXPECT_NEAR(l.stiffness, 1.5 / 0.035, 1e-9);
  BladderHysteresisParams off;
  off.enabled = false;
  EXPECT_EQ(bladder_hysteresis_levels(off, 75.0).half_width, 0.0);
  BladderHysteresisParams vertical;
  vertical.boundary_angle = 0.0;  // ramp collapses into the step: pure Coulomb
  EXPECT_NEAR(bladder_hysteresis_levels(vertical, 75.0).step, 1.5, 1e-12);
  EXPECT_EQ(bladder_hysteresis_levels(vertical, 75.0).stiffness, 0.0);
}

// Torque along a triangle wave 0 -> +a -> -a -> +a in increments of `step`.
std::vector<std::array<double, 2>> drive_triangle(double a, double step) {
  BladderHysteresis h(nominal_levels());
  h.reset(0.0);
  std::vector<std::array<double, 2>> out;
  const auto go = [&](double from, double to) {
    const int n = static_cast<int>(std::lround(std::abs(to - from) / step));
    for (int i = 1; i <= n; ++i) {
      const double th = from + (to - from) * i / n;
      out.push_back({th, h.update(th)});
    }
  };
  go(0.0, a);
  go(a, -a);
  go(-a, a);
  return out;
}

TEST(BladderHysteresis, LoopIsTheModifiedTrapezoidOfFig2b) {
  const double a = 0.1, step = 1e-4;
  const auto loop = drive_triangle(a, step);
  const std::size_t up = static_cast<std::size_t>(std::lround(a / step));  // index of theta = +a
  // Saturated at the top of the first stroke.
  EXPECT_NEAR(loop[up - 1][1], 1.5, 1e-12);
  // A-B: the first sample after the reversal has dropped by the step (2 h_s
  // = 1.5 N m) plus the ramp over one increment.
  const double k = 1.5 / 0.035;
  EXPECT_NEAR(loop[up][1], 1.5 - 1.5 - k * step, 1e-9);
  // B-C: linear in the travel d since the reversal, T = -k d, until the
  // boundary -1.5 N m at d = 0.035 rad; then flat (C-D).
  for (std::size_t i = up; i < up + static_cast<std::size_t>(std::lround(2 * a / step)); ++i) {
    const double d = a - loop[i][0];
    const double expected = std::max(-k * d, -1.5);
    ASSERT_NEAR(loop[i][1], expected, 1e-9) << "travel " << d;
  }
  // The other branch is the mirror image (D-E-F).
  const std::size_t down = up + static_cast<std::size_t>(std::lround(2 * a / step));
  for (std::size_t i = down; i < loop.size(); ++i) {
    const double d = loop[i][0] + a;
    ASSERT_NEAR(loop[i][1], std::min(k * d, 1.5), 1e-9) << "travel " << d;
  }
  std::printf("  loop: +1.5 N m -> step to %.3f N m -> ramp %.1f N m/rad -> -1.5 N m after %.3f rad\n",
              loop[up][1] + k * step, k, 0.035);
}

TEST(BladderHysteresis, RateIndependentAndPartialLoopsKeepTheSlope) {
  // The element has no time input: a 100x coarser sampling (100x faster at
  // the same control rate) of the same path gives the same torque wherever
  // the samples coincide.
  const auto fine = drive_triangle(0.1, 1e-5);
  const auto coarse = drive_triangle(0.1, 1e-3);
  int compared = 0;
  for (std::size_t i = 0; i < coarse.size(); ++i) {
    const auto& c = coarse[i];
    const auto& f = fine[(i + 1) * 100 - 1];
    ASSERT_NEAR(c[0], f[0], 1e-12);
    // Right after a reversal the coarse path has not sampled the reversal
    // point itself; the ramp makes up the difference within one increment.
    ASSERT_NEAR(c[1], f[1], 1.5 / 0.035 * 1e-3 + 1e-9);
    if (std::abs(c[1] - f[1]) < 1e-9) ++compared;
  }
  EXPECT_GT(compared, static_cast<int>(coarse.size()) - 6);

  // Reversal inside the ramp: from negative saturation up by 0.01 rad, then
  // back: step of 2 h_s, same slope.
  BladderHysteresis h(nominal_levels());
  h.reset(0.0);
  h.update(-0.1);  // saturated negative: -1.5
  EXPECT_NEAR(h.torque(), -1.5, 1e-12);
  const double k = 1.5 / 0.035;
  EXPECT_NEAR(h.update(-0.09), -1.5 + 1.5 + k * 0.01, 1e-12);
  EXPECT_NEAR(h.update(-0.095), k * 0.01 - 1.5 - k * 0.005, 1e-12);
}

// -------------------------------------------------------- Coulomb brake

PneumaticRotaryParams brake_params(double level) {
  PneumaticRotaryParams p = bare_params();
  p.brake.enabled = true;
  p.brake.level = level;
  return p;
}

TEST(CoulombBrake, HoldsBelowItsLevelAndCarriesExactlyTheAppliedTorque) {
  // 10 % = 7.5 N m. u = 0.345 V makes a blocked dp of 2 C1 x / C2 = 41.7 kPa,
  // alpha dp = 5 N m: below the level, so the load must not move at all.
  PneumaticRotaryPlant plant(brake_params(0.10));
  EXPECT_NEAR(plant.brake_level(), 7.5, 1e-12);
  double worst_excess = -INFINITY;
  run(plant, 0.345, 5.0, [&](double, const PneumaticRotaryPlant& q) {
    const auto m = measured(q);
    ASSERT_EQ(m[sig::kTheta], 0.0);
    ASSERT_EQ(m[sig::kOmega], 0.0);
    ASSERT_EQ(q.state().mode, RotaryLoadMode::kStuck);
    // Opposes but never exceeds the applied torque (Fig. 2d).
    ASSERT_NEAR(m[sig::kSimTFriction], 1.2e-4 * m[sig::kDp], 1e-12);
    worst_excess = std::max(worst_excess, std::abs(m[sig::kSimTFriction]) - 7.5);
  });
  const double applied = 1.2e-4 * measured(plant)[sig::kDp];
  std::printf("  applied %.3f N m held by a 7.5 N m brake, friction %.3f N m\n", applied,
              measured(plant)[sig::kSimTFriction]);
  EXPECT_NEAR(applied, 1.2e-4 * 2.0 * 1.5 * 0.161e-3 * 0.345 / 4e-9, 0.01);
  EXPECT_LT(worst_excess, -2.0);

  // With the dither on, the 50 Hz pressure ripple must not make it creep.
  PneumaticRotaryParams pd = brake_params(0.10);
  pd.dither = true;
  PneumaticRotaryPlant dithered(pd);
  run(dithered, 0.345, 3.0);
  EXPECT_EQ(dithered.state().theta, 0.0);
}

TEST(CoulombBrake, BreaksAwayAtItsLevelAndThenSlidesAtIt) {
  // u = 1 V: blocked dp would reach 121 kPa (14.5 N m); the load starts to
  // move when alpha dp passes 7.5 N m and then the brake stays at 7.5 N m.
  PneumaticRotaryPlant plant(brake_params(0.10));
  double applied_at_breakaway = NAN;
  double prev_applied = 0.0;
  bool moving = false;
  run(plant, 1.0, 3.0, [&](double, const PneumaticRotaryPlant& q) {
    const auto m = measured(q);
    if (!moving && q.state().mode != RotaryLoadMode::kStuck) {
      moving = true;
      applied_at_breakaway = prev_applied;
    }
    if (q.state().mode == RotaryLoadMode::kSlidingPositive) {
      ASSERT_EQ(m[sig::kSimTFriction], 7.5);
    }
    ASSERT_LE(std::abs(m[sig::kSimTFriction]), 7.5);
    prev_applied = 1.2e-4 * m[sig::kDp];
  }, 1e-4);
  std::printf("  stuck until alpha dp = %.4f N m (level 7.5)\n", applied_at_breakaway);
  EXPECT_TRUE(moving);
  EXPECT_NEAR(applied_at_breakaway, 7.5, 0.05);
  EXPECT_GT(plant.state().theta, 0.05);
}

TEST(CoulombBrake, HeldTorqueIsSharedWithTheHysteresisStepWithinEachLevel) {
  // Brake 2 % (1.5 N m) and bladder step part 0.75 N m hold together up to
  // 2.25 N m; u = 0.12 V makes alpha dp = 1.74 N m blocked.
  PneumaticRotaryParams p = brake_params(0.02);
  p.hysteresis.enabled = true;
  PneumaticRotaryPlant plant(p);
  run(plant, 0.12, 5.0, [&](double, const PneumaticRotaryPlant& q) {
    const auto m = measured(q);
    ASSERT_EQ(m[sig::kTheta], 0.0);
    ASSERT_NEAR(m[sig::kSimTHysteresis] + m[sig::kSimTFriction], 1.2e-4 * m[sig::kDp], 1e-12);
    ASSERT_LE(std::abs(m[sig::kSimTFriction]), 1.5 + 1e-12);
    ASSERT_LE(std::abs(m[sig::kSimTHysteresis]), 0.75 + 1e-12);  // ramp unloaded: step part only
  });
  const auto m = measured(plant);
  std::printf("  applied %.3f N m = brake %.3f + hysteresis %.3f\n", 1.2e-4 * m[sig::kDp], m[sig::kSimTFriction],
              m[sig::kSimTHysteresis]);
  EXPECT_NEAR(m[sig::kSimTFriction], 2.0 * m[sig::kSimTHysteresis], 1e-12);  // in proportion 1.5 : 0.75
}

TEST(CoulombBrake, StickSlipHelpers) {
  EXPECT_EQ(breakaway_direction(1.0, 2.0), 0);
  EXPECT_EQ(breakaway_direction(-2.0, 2.0), 0);
  EXPECT_EQ(breakaway_direction(2.5, 2.0), 1);
  EXPECT_EQ(breakaway_direction(-2.5, 2.0), -1);
  EXPECT_EQ(breakaway_direction(1e-300, 0.0), 1);
  EXPECT_EQ(breakaway_direction(0.0, 0.0), 0);
  EXPECT_EQ(holding_share(3.0, 1.0, 3.0), 1.0);
  EXPECT_EQ(holding_share(3.0, 1.0, 0.0), 0.0);  // no division by zero
  CoulombBrakeParams off;
  EXPECT_EQ(coulomb_brake_level(off, 75.0), 0.0);
}

// --------------------------------------------- hysteresis inside the plant

// Relay drive: +U until theta > +a, then -U until theta < -a, and so on.
// Records (theta, travel since the last reversal, direction, T_h) while the
// load slides, and checks the stuck samples on the way.
struct LoopSample {
  double theta, travel, t_h;
  int dir;
};

std::vector<LoopSample> relay_loop(double u_mag, double a, double seconds, int* reversals) {
  PneumaticRotaryParams p = bare_params();
  p.hysteresis.enabled = true;  // nominal +-2 %
  PneumaticRotaryPlant plant(p);
  const auto levels = plant.hysteresis_levels();
  std::vector<LoopSample> out;
  double u = u_mag;
  int last_dir = 0;
  double theta_rev = 0.0, extreme = 0.0;
  *reversals = 0;
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int i = 0; i < n; ++i) {
    plant.advance({&u, 1}, kDt);
    const auto s = plant.state();
    const auto m = measured(plant);
    if (s.theta > a) u = -u_mag;
    if (s.theta < -a) u = u_mag;
    if (s.mode == RotaryLoadMode::kStuck) {
      // At rest the element carries the residual but never more than the
      // boundary of the trapezoid.
      EXPECT_LE(std::abs(m[sig::kSimTHysteresis]), levels.half_width + 1e-9);
      extreme = s.theta;
      continue;
    }
    const int dir = s.mode == RotaryLoadMode::kSlidingPositive ? 1 : -1;
    if (dir != last_dir) {
      // The reversal point is the extreme of the previous stretch (theta is
      // frozen while stuck); the sampled extreme misses the true one by at
      // most a dt^2 / 2 with a <= 73 N m / 1.7 kg m^2 = 43 rad/s^2, i.e.
      // 1.3e-4 rad or 5.7e-3 N m on the ramp.
      if (last_dir != 0) ++*reversals;
      theta_rev = extreme;
      last_dir = dir;
    }
    extreme = dir > 0 ? std::max(extreme, s.theta) : std::min(extreme, s.theta);
    out.push_back({s.theta, std::abs(s.theta - theta_rev), m[sig::kSimTHysteresis], dir});
  }
  return out;
}

// Fig. 2b after a reversal from saturation at -dir H: the step takes it to
// -H + 2 h_s = 0, then the ramp k d until +H: T = dir min(k d, H).
double trapezoid(double travel, int dir) {
  const double k = 1.5 / 0.035;
  return dir * std::min(k * travel, 1.5);
}

TEST(BladderHysteresisInPlant, SameTrapezoidAtVeryDifferentSpeeds) {
  // Open-loop velocity ~ 0.376 rad/s per volt less the leakage needed to hold
  // the hysteresis torque: about 0.04 rad/s at 0.2 V; at 3 V the relay
  // overshoots into swings of several rad/s.
  int rev_slow = 0, rev_fast = 0;
  const auto slow = relay_loop(0.2, 0.1, 40.0, &rev_slow);
  const auto fast = relay_loop(3.0, 0.1, 8.0, &rev_fast);
  double v_slow = 0.0, v_fast = 0.0;
  for (std::size_t i = 1; i < slow.size(); ++i) v_slow = std::max(v_slow, std::abs(slow[i].theta - slow[i - 1].theta) / kDt);
  for (std::size_t i = 1; i < fast.size(); ++i) v_fast = std::max(v_fast, std::abs(fast[i].theta - fast[i - 1].theta) / kDt);
  // Compare with the hand-drawn trapezoid on every stretch that started from
  // saturation (all but the first), binned by travel since the reversal.
  const auto worst = [](const std::vector<LoopSample>& loop, double* max_travel) {
    double w = 0.0;
    *max_travel = 0.0;
    bool first_stretch = true;
    int dir0 = loop.empty() ? 0 : loop.front().dir;
    for (const auto& s : loop) {
      if (s.dir != dir0) first_stretch = false;
      if (first_stretch) continue;
      w = std::max(w, std::abs(s.t_h - trapezoid(s.travel, s.dir)));
      *max_travel = std::max(*max_travel, s.travel);
    }
    return w;
  };
  double travel_slow = 0.0, travel_fast = 0.0;
  const double w_slow = worst(slow, &travel_slow), w_fast = worst(fast, &travel_fast);
  std::printf("  slow: peak %.3f rad/s, %d reversals, worst |T - trapezoid| %.2e N m\n", v_slow, rev_slow, w_slow);
  std::printf("  fast: peak %.3f rad/s, %d reversals, worst |T - trapezoid| %.2e N m\n", v_fast, rev_fast, w_fast);
  EXPECT_GT(v_fast, 20.0 * v_slow);
  EXPECT_GE(rev_slow, 4);
  EXPECT_GE(rev_fast, 4);
  EXPECT_GT(travel_slow, 0.1);  // the stretches pass the boundary
  EXPECT_GT(travel_fast, 0.1);
  EXPECT_LT(w_slow, 6e-3);  // sampling of the reversal point only (see relay_loop)
  EXPECT_LT(w_fast, 6e-3);
}

TEST(BladderHysteresisInPlant, HeldLoadInsideTheStepBandDoesNotChatter) {
  // At rest the step part holds up to h_s = 0.75 N m (the ramp is unloaded
  // at reset). A blocked dp of 2 C1 x / C2 at u = 0.03 V gives 0.43 N m, and
  // the 50 Hz dither adds a ripple of about +-0.13 N m (+-540 Pa per
  // bladder): held, without a single mode change.
  PneumaticRotaryParams p;  // nominal: dither and +-2 % hysteresis
  PneumaticRotaryPlant plant(p);
  int changes = 0;
  RotaryLoadMode last = plant.state().mode;
  run(plant, 0.03, 5.0, [&](double, const PneumaticRotaryPlant& q) {
    if (q.state().mode != last) ++changes;
    last = q.state().mode;
  });
  const auto m = measured(plant);
  std::printf("  applied %.3f N m (at a trough of the ripple), T_h %.3f N m, theta %.3g rad, %d mode changes\n",
              1.2e-4 * m[sig::kDp],
              m[sig::kSimTHysteresis], m[sig::kTheta], changes);
  EXPECT_EQ(changes, 0);
  EXPECT_EQ(m[sig::kTheta], 0.0);
  EXPECT_NEAR(m[sig::kSimTHysteresis], 1.2e-4 * m[sig::kDp], 1e-12);

  // Above the band (u = 0.1 V: 1.45 N m) the same load moves.
  plant.reset();
  run(plant, 0.1, 5.0);
  EXPECT_GT(plant.state().theta, 0.001);
}

}  // namespace
}  // namespace rigctl
