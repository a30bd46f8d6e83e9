// The quarter car's bearing friction (seed paper 000): the friction law's
// Stribeck dip, hold and slide about breakaway, and the body mode it stops,
// against the breakaway force written out by hand from docs/rig-models.md
// 1.5.4, not against numbers read back from the implementation.
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

#include "plant/quarter_car/bearing_friction.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "allocation_counter.hpp"
#include "quarter_car_plant_stepping.hpp"

namespace rigctl {
namespace {

using namespace quarter_car_test;

TEST(QuarterCarBearing, FrictionLawHasAStribeckDipFromBreakawayToCoulomb) {
  BearingFrictionParams f;
  f.enabled = true;
  const BearingFrictionLevels lv = bearing_friction_levels(f, 240.0 * 9.81, 0.0, 0.0);
  // Static preload only: F_n = Mb g / tan(62 deg).
  EXPECT_NEAR(lv.normal, 240.0 * 9.81 / std::tan(f.construction_angle), 1e-9);
  EXPECT_NEAR(f.construction_angle, 62.0 * std::numbers::pi / 180.0, 1e-4);
  EXPECT_NEAR(lv.coulomb, f.coulomb_base + f.normal_coefficient * lv.normal, 1e-9);
  EXPECT_NEAR(lv.breakaway, lv.coulomb + f.stiction_excess, 1e-9);
  EXPECT_NEAR(lv.breakaway, 200.0, 10.0);  // "about 200 N"
  // Force-continuous at breakaway, then dips monotonically towards F_c + D v.
  EXPECT_DOUBLE_EQ(sliding_friction(f, lv, +1, 0.0), lv.breakaway);
  EXPECT_DOUBLE_EQ(sliding_friction(f, lv, -1, 0.0), -lv.breakaway);
  double previous = lv.breakaway;
  for (double v = 0.001; v <= 0.03; v += 0.001) {
    const double dry = sliding_friction(f, lv, +1, v) - f.viscous * v;
    EXPECT_LT(dry, previous);
    previous = dry;
    EXPECT_DOUBLE_EQ(-sliding_friction(f, lv, -1, -v), sliding_friction(f, lv, +1, v));  // odd
  }
  EXPECT_NEAR(sliding_friction(f, lv, +1, 0.1), lv.coulomb + f.viscous * 0.1, 1e-6);
  // Eq. 14 sign: compressing the suspension (x_w > x_b) steepens nothing but
  // turns the linkage towards the rails, raising the side load.
  EXPECT_GT(bearing_friction_levels(f, 240.0 * 9.81, 0.0, 0.01).normal, lv.normal);
  // Guards: absurd deflections stay finite.
  EXPECT_TRUE(std::isfinite(bearing_friction_levels(f, 240.0 * 9.81, 1e4, 5.0).breakaway));
  EXPECT_TRUE(std::isfinite(bearing_friction_levels(f, 240.0 * 9.81, -1e4, -5.0).breakaway));
}

TEST(QuarterCarBearing, HoldsBelowBreakawayWithoutChatterAndSlidesAbove) {
  const QuarterCarParams p = closed_valve_params(true);
  // Find the breakaway for the held configuration (F_n depends on F_susp).
  double f_break = 200.0;
  for (int i = 0; i < 50; ++i) f_break = breakaway(p, held_state(p, f_break));

  for (double fraction : {0.5, 0.99}) {
    QuarterCarPlant plant(p);
    const QuarterCarState s0 = held_state(p, fraction * f_break);
    plant.set_state(s0);
    int not_stuck = 0;
    double worst_force_error = 0.0;
    // 2 s = 16000 sub-steps under a constant force below breakaway.
    run(plant, 0.0, 2.0, [&](double, const QuarterCarPlant& q) {
      const auto m = measured(q);
      not_stuck += m[sig::kSimBearingStuck] != 1.0;
      EXPECT_EQ(q.state().x_b, s0.x_b);
      EXPECT_EQ(q.state().v_b, 0.0);
      worst_force_error = std::max(worst_force_error, std::abs(m[sig::kSimFBearing] - fraction * f_break));
    });
    EXPECT_EQ(not_stuck, 0) << "at " << fraction << " of breakaway";
    EXPECT_LT(worst_force_error, 1e-3);  // the bearing carries exactly F_susp
  }

  // Just above breakaway the body leaves at once, in the direction of the force.
  for (double sign : {1.0, -1.0}) {
    QuarterCarPlant plant(p);
    double f = f_break;
    if (sign < 0) {
      f = -200.0;
      for (int i = 0; i < 50; ++i) f = -breakaway(p, held_state(p, f));
    }
    plant.set_state(held_state(p, 1.01 * f));
    run(plant, 0.0, kDt);
    const auto m = measured(plant);
    EXPECT_EQ(m[sig::kSimBearingStuck], 0.0);
    EXPECT_GT(sign * plant.state().v_b, 0.0);
  }

  // Without friction the same sub-breakaway force moves the body at once, and
  // no bearing force is reported.
  QuarterCarPlant free_plant(closed_valve_params(false));
  free_plant.set_state(held_state(p, 0.5 * f_break));
  run(free_plant, 0.0, kDt);
  const auto m = measured(free_plant);
  EXPECT_EQ(m[sig::kSimFBearing], 0.0);
  EXPECT_EQ(m[sig::kSimBearingStuck], 0.0);
  // a = F / Mb for one period, less a little for the spring unloading.
  EXPECT_NEAR(free_plant.state().v_b, 0.5 * f_break / p.mass_body * kDt, 0.05 * 0.5 * f_break / p.mass_body * kDt);
  std::printf("  breakaway of the held body: %.2f N (ks x %.2f mm)\n", f_break, f_break / p.spring_stiffness * 1e3);
}

TEST(QuarterCarBearing, DrivenWheelBreaksBodyLooseAtBreakawayAndTracesStribeckCurve) {
  QuarterCarParams p;
  p.bearing_friction.enabled = true;
  const auto& f = p.bearing_friction;
  QuarterCarPlant plant(p);
  // Extend slowly (about 40 mm/s): the wheel loads the spring until the
  // bearing lets go, then the body stick-slips behind it.
  const double u = QuarterCarPlant::rest_valve_offset(p) + 0.15;
  bool first_stick = true;
  int toggles_while_first_stuck = 0;
  double break_force = 0.0, break_limit = 0.0, previous_force = 0.0, previous_limit = 0.0;
  struct Point {
    double v, friction, coulomb, breakaway;
  };
  std::vector<Point> slip;
  slip.reserve(1000);
  bool was_stuck = true;
  run(plant, u, 1.5, [&](double, const QuarterCarPlant& q) {
    const QuarterCarState s = q.state();
    const auto m = measured(q);
    const bool stuck = m[sig::kSimBearingStuck] == 1.0;
    const double fs = suspension_force(p, s);
    if (first_stick) {
      if (stuck) {
        toggles_while_first_stuck += !was_stuck;
        EXPECT_EQ(s.x_b, 0.0);
        EXPECT_EQ(s.v_b, 0.0);
        EXPECT_LE(std::abs(fs), breakaway(p, s) * (1 + 1e-12));
        EXPECT_NEAR(m[sig::kSimFBearing], fs, 1e-9);
        previous_force = fs;
        previous_limit = breakaway(p, s);
      } else {
        first_stick = false;
        break_force = fs;
        break_limit = breakaway(p, s);
      }
    } else if (!stuck) {
      const double lim = breakaway(p, s);
      slip.push_back({s.v_b, m[sig::kSimFBearing], lim - f.stiction_excess, lim});
    }
    was_stuck = stuck;
  });
  ASSERT_FALSE(first_stick) << "the body never broke loose";
  EXPECT_EQ(toggles_while_first_stuck, 0);
  // It held up to the breakaway force and let go at it (the force grows by
  // about 3 N per period here).
  EXPECT_LT(previous_force, previous_limit);
  EXPECT_GE(break_force, break_limit);
  EXPECT_LT(break_force, break_limit + 5.0);
  EXPECT_NEAR(break_force / p.spring_stiffness, 0.0069, 0.0007);  // the paper's 6.9 mm stick limit
  std::printf("  body broke loose at F_susp = %.2f N (breakaway %.2f N)\n", break_force, break_limit);

  // Friction against velocity while sliding: breakaway at low speed, down
  // to the Coulomb level plus viscous at high speed.
  int low = 0, high = 0;
  double worst_low = 0.0, worst_high = 0.0;
  double max_v = 0.0;
  for (const Point& pt : slip) {
    const double speed = std::abs(pt.v);
    max_v = std::max(max_v, speed);
    if (speed > 1e-6) {
      EXPECT_GT(pt.friction * pt.v, 0.0) << "friction must oppose sliding";
    }
    const double dry = std::abs(pt.friction - f.viscous * pt.v);
    if (speed < 0.1 * f.stribeck_velocity) {
      ++low;
      worst_low = std::max(worst_low, std::abs(dry - pt.breakaway));
    } else if (speed > 3.0 * f.stribeck_velocity) {
      ++high;
      worst_high = std::max(worst_high, std::abs(dry - pt.coulomb));
    }
  }
  std::printf("  slip samples: %d below 1.5 mm/s, %d above 45 mm/s (max %.3f m/s); worst dev %.2f N, %.2f N\n",
              low, high, max_v, worst_low, worst_high);
  ASSERT_GE(low, 3);
  ASSERT_GE(high, 10);
  EXPECT_LT(worst_low, 0.02 * f.stiction_excess);   // within 2 N of breakaway
  EXPECT_LT(worst_high, 0.02 * f.stiction_excess);  // Stribeck excess gone: exp(-9)
}

// ------------------------------------------------------ free body oscillation

struct Ringdown {
  double p2p_late;       // peak-to-peak body displacement over the last 2 s [m]
  double final_force;    // |ks (x_w - x_b)| at the end [N]
  double final_limit;    // breakaway at the end [N]
  bool ends_stuck;
  int stick_changes;
  std::vector<double> up_crossings;  // times x_w - x_b - mean crosses upward
  std::vector<double> peaks;         // successive maxima of x_b
};

Ringdown ring_down(bool friction) {
  const QuarterCarParams p = closed_valve_params(friction);
  QuarterCarPlant plant(p);
  QuarterCarState s = plant.state();
  s.x_b = -0.010;  // body 10 mm below its equilibrium relative to the wheel
  plant.set_state(s);
  Ringdown r{};
  double lo = 1e9, hi = -1e9, prev_xb = s.x_b, prev_dxb = 0.0;
  bool stuck = true;
  run(plant, 0.0, 4.0, [&](double t, const QuarterCarPlant& q) {
    const QuarterCarState st = q.state();
    if (t > 2.0) {
      lo = std::min(lo, st.x_b);
      hi = std::max(hi, st.x_b);
    }
    const double dxb = st.x_b - prev_xb;
    if (prev_dxb > 0.0 && dxb <= 0.0) r.peaks.push_back(prev_xb);
    if (prev_xb < 0.0 && st.x_b >= 0.0) r.up_crossings.push_back(t);
    prev_dxb = dxb;
    prev_xb = st.x_b;
    const bool now = measured(q)[sig::kSimBearingStuck] == 1.0;
    r.stick_changes += now != stuck;
    stuck = now;
  });
  const QuarterCarState e = plant.state();
  r.p2p_late = hi - lo;
  r.final_force = std::abs(p.spring_stiffness * (e.x_w - e.x_b));
  r.final_limit = breakaway(p, e);
  r.ends_stuck = stuck;
  return r;
}

TEST(QuarterCarBearing, FrictionStopsTheBodyModeThatTheDamperBarelyDamps) {
  const Ringdown off = ring_down(false);
  const Ringdown on = ring_down(true);
  std::printf("  ring-down: p2p over 2-4 s %.3f mm without friction, %.3f mm with; ends held at %.1f N < %.1f N\n",
              off.p2p_late * 1e3, on.p2p_late * 1e3, on.final_force, on.final_limit);

  // Without friction: the 1.75 Hz, 4.9 %-damped body mode of docs/rig-models.md 1.7.
  ASSERT_GE(off.up_crossings.size(), 5u);
  const double period = (off.up_crossings.back() - off.up_crossings.front()) / (off.up_crossings.size() - 1);
  EXPECT_NEAR(1.0 / period, 1.75, 0.05);
  ASSERT_GE(off.peaks.size(), 4u);
  const double zeta = std::log(off.peaks[0] / off.peaks[3]) / 3.0 / (2.0 * std::numbers::pi);
  EXPECT_NEAR(zeta, 0.049, 0.01);
  std::printf("  body mode without friction: %.3f Hz, damping ratio %.4f\n", 1.0 / period, zeta);
  EXPECT_GT(off.p2p_late, 0.004);

  // With friction the body stops within the first swing and stays held,
  // inside the stick band, with no further toggling.
  EXPECT_TRUE(on.ends_stuck);
  EXPECT_EQ(on.p2p_late, 0.0);
  EXPECT_LT(on.final_force, on.final_limit);
  EXPECT_GE(on.stick_changes, 2);  // it did slide, then stuck
  EXPECT_LE(on.stick_changes, 6);
}

}  // namespace
}  // namespace rigctl
