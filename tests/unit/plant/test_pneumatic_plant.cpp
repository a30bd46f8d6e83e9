// Open-loop checks of the rotary pneumatic plant against hand calculations
// from docs/rig-models.md section 2 and seed 002 eqs. 2-17, not against
// numbers read back from the implementation.
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


namespace rigctl {
namespace {

namespace sig = pneumatic_rotary_signal;

constexpr double kDt = 0.0025;  // control period [s]
constexpr double kPi = std::numbers::pi;

// Hand values from the nominal parameters (docs/rig-models.md 2.5).
constexpr double kGammaRT = 1.4 * 287.0 * 293.0;                  // gamma R T [J/kg]
constexpr double kTau = 0.25e-3 / (kGammaRT * 4e-9);              // V / (gamma R T C2) = 0.531 s
constexpr double kStiffness = 2.0 * 1.4 * 4.5e5 * 1.2e-4 * 1.2e-4 / 0.25e-3;  // 2 gamma Pq alpha^2 / V = 72.6 N m/rad

// The linear plant alone: no dither, no hysteresis, no brake.
PneumaticRotaryParams bare_params() {
  PneumaticRotaryParams p;
  p.dither = false;
  p.hysteresis.enabled = false;
  p.brake.enabled = false;
  return p;
}

std::array<double, sig::kCount> measured(const PneumaticRotaryPlant& plant) {
  std::array<double, sig::kCount> out{};
  plant.measure(out);
  return out;
}

// Advances with u held for `seconds` in steps of dt and calls f(t, plant)
// after each step.
template <typename F>
void run(PneumaticRotaryPlant& plant, double u, double seconds, F&& f, double dt = kDt) {
  const int n = static_cast<int>(std::lround(seconds / dt));
  const double t0 = plant.state().time;
  for (int i = 1; i <= n; ++i) {
    plant.advance({&u, 1}, dt);
    f(t0 + i * dt, plant);
  }
}
void run(PneumaticRotaryPlant& plant, double u, double seconds) {
  run(plant, u, seconds, [](double, const PneumaticRotaryPlant&) {});
}

// Times where a sampled signal crosses zero downwards, linearly interpolated.
struct Crossings {
  std::vector<double> down;
  std::vector<double> peaks;  // |value| of the extreme between successive crossings
};

// Free oscillation with the valve closed from omega(0) = omega0: returns the
// downward zero crossings of omega and its positive peaks.
Crossings free_oscillation(const PneumaticRotaryParams& p, double omega0, double seconds) {
  PneumaticRotaryPlant plant(p);
  PneumaticRotaryState s;
  s.omega = omega0;
  plant.set_state(s);
  Crossings c;
  double prev = omega0, prev_t = 0.0, peak = omega0;
  run(plant, 0.0, seconds, [&](double t, const PneumaticRotaryPlant& q) {
    const double w = q.state().omega;
    peak = std::max(peak, w);
    if (prev > 0.0 && w <= 0.0) {
      c.down.push_back(prev_t + (t - prev_t) * prev / (prev - w));
      c.peaks.push_back(peak);
      peak = 0.0;
    }
    prev = w;
    prev_t = t;
  }, 1e-4);
  return c;
}

// ---------------------------------------------------------------- interface

TEST(PneumaticRotaryPlant, SignalsAndCommandsInDocumentedOrder) {
  PneumaticRotaryPlant plant{PneumaticRotaryParams{}};
  const char* names[] = {"theta", "dp", "omega", "sim_pa", "sim_pb", "sim_x", "sim_t_hysteresis", "sim_t_friction"};
  const char* units[] = {"rad", "Pa", "rad/s", "Pa", "Pa", "m", "N m", "N m"};
  ASSERT_EQ(plant.signals().size(), sig::kCount);
  for (std::size_t i = 0; i < sig::kCount; ++i) {
    EXPECT_EQ(plant.signals()[i].name, names[i]);
    EXPECT_EQ(plant.signals()[i].unit, units[i]);
  }
  ASSERT_EQ(plant.commands().size(), 1u);
  EXPECT_EQ(plant.commands()[0].name, "u");
  EXPECT_EQ(plant.commands()[0].unit, "V");
}

TEST(PneumaticRotaryPlant, AdvanceAndMeasureDoNotAllocate) {
  PneumaticRotaryParams p;  // dither, hysteresis on
  p.brake.enabled = true;
  p.brake.level = 0.02;
  PneumaticRotaryPlant plant(p);
  std::array<double, sig::kCount> out{};
  const long before = rigctl::test::allocation_count();
  for (int i = 0; i < 2000; ++i) {
    const double u = (i / 200) % 2 == 0 ? 1.5 : -1.5;  // stick, slip and reversals
    plant.advance({&u, 1}, kDt);
    plant.measure(out);
  }
  EXPECT_EQ(rigctl::test::allocation_count() - before, 0);
  EXPECT_GT(std::abs(out[sig::kTheta]), 0.0);
}

TEST(PneumaticRotaryPlant, ResetIsRestAtMidStrokeWithDitherPhaseZero) {
  PneumaticRotaryPlant plant{PneumaticRotaryParams{}};
  run(plant, 2.0, 1.0);
  plant.reset();
  const auto s = plant.state();
  EXPECT_EQ(s.theta, 0.0);
  EXPECT_EQ(s.omega, 0.0);
  EXPECT_EQ(s.p_a, 0.0);
  EXPECT_EQ(s.p_b, 0.0);
  EXPECT_EQ(s.time, 0.0);
  EXPECT_EQ(s.mode, RotaryLoadMode::kStuck);
  EXPECT_EQ(measured(plant)[sig::kSimX], 0.0);  // sin(0) with u = 0
  EXPECT_EQ(measured(plant)[sig::kSimTHysteresis], 0.0);

  // Deterministic from reset: the same commands give bit-identical runs.
  std::vector<double> first, second;
  for (auto* trace : {&first, &second}) {
    plant.reset();
    run(plant, 1.0, 0.5, [&](double, const PneumaticRotaryPlant& q) { trace->push_back(q.state().theta); });
  }
  EXPECT_EQ(first, second);
}

TEST(PneumaticRotaryPlant, PositiveCommandDrivesThetaUpThroughBladderA) {
  PneumaticRotaryPlant plant{bare_params()};
  run(plant, 0.5, 0.02);
  const auto early = plant.state();
  EXPECT_GT(early.p_a, 0.0);
  EXPECT_LT(early.p_b, 0.0);
  EXPECT_GT(measured(plant)[sig::kDp], 0.0);
  run(plant, 0.5, 1.0);
  EXPECT_GT(plant.state().theta, 0.05);
  EXPECT_GT(plant.state().omega, 0.0);
}

TEST(PneumaticRotaryPlant, NonFiniteCommandIsIgnored) {
  PneumaticRotaryPlant plant{PneumaticRotaryParams{}};
  const double bad = NAN;
  plant.advance({&bad, 1}, kDt);
  for (double v : measured(plant)) EXPECT_TRUE(std::isfinite(v));
}

// ------------------------------------------------------ chambers and valve

TEST(PneumaticChambers, BlockedLoadPressureRisesWithTimeConstantTau) {
  // Spool held open, load held by a brake stronger than the stall torque:
  // omega = 0, so dp_a/dt = (gamma R T / V)(C1 x - C2 p_a) and
  // p_a = (C1 x / C2)(1 - exp(-t / tau)), p_b = -p_a, dp = 2 C1 x / C2.
  PneumaticRotaryParams p = bare_params();
  p.brake.enabled = true;
  p.brake.level = 2.0;  // 150 N m
  PneumaticRotaryPlant plant(p);
  const double u = 2.0;
  const double x = 0.161e-3 * u;
  const double p_ss = 1.5 * x / 4e-9;  // 1.21 bar
  std::printf("  tau = %.4f s, p_a -> %.0f Pa, dp -> %.0f Pa\n", kTau, p_ss, 2.0 * p_ss);
  EXPECT_NEAR(kTau, 0.53, 0.005);  // docs/rig-models.md 2.7 "Behaviour to expect"

  run(plant, u, kTau, [](double, const PneumaticRotaryPlant&) {}, kTau / 200.0);
  EXPECT_NEAR(plant.state().time, kTau, 1e-12);
  EXPECT_NEAR(plant.state().p_a / p_ss, 1.0 - std::exp(-1.0), 1e-6);
  EXPECT_NEAR(plant.state().p_b / p_ss, -(1.0 - std::exp(-1.0)), 1e-6);
  run(plant, u, 9.0 * kTau, [](double, const PneumaticRotaryPlant&) {}, kTau / 200.0);
  const auto m = measured(plant);
  EXPECT_NEAR(m[sig::kDp], 2.0 * p_ss * (1.0 - std::exp(-10.0)), 1.0);
  EXPECT_EQ(m[sig::kTheta], 0.0);  // held
  EXPECT_EQ(m[sig::kOmega], 0.0);
  EXPECT_DOUBLE_EQ(m[sig::kSimX], x);
  // The brake carries exactly the pressure torque.
  EXPECT_NEAR(m[sig::kSimTFriction], 1.2e-4 * m[sig::kDp], 1e-9);
}

TEST(PneumaticChambers, ClosedValveStiffnessIs72NmPerRad) {
  // No leakage (C2 = 0), valve closed: p_a = -gamma Pq alpha theta / V exactly,
  // so the torque alpha (p_a - p_b) = -K theta with K = 2 gamma Pq alpha^2 / V.
  PneumaticRotaryParams p = bare_params();
  p.flow_pressure_coefficient = 0.0;
  PneumaticRotaryPlant plant(p);
  PneumaticRotaryState s;
  s.omega = 0.5;
  plant.set_state(s);
  double worst = 0.0, max_theta = 0.0;
  run(plant, 0.0, 2.0, [&](double, const PneumaticRotaryPlant& q) {
    const auto m = measured(q);
    max_theta = std::max(max_theta, std::abs(m[sig::kTheta]));
    if (std::abs(m[sig::kTheta]) > 0.01) worst = std::max(worst, std::abs(-1.2e-4 * m[sig::kDp] / m[sig::kTheta] / kStiffness - 1.0));
  });
  std::printf("  K = %.2f N m/rad, amplitude %.4f rad, worst relative deviation %.2e\n", kStiffness, max_theta, worst);
  EXPECT_NEAR(kStiffness, 72.6, 0.05);
  EXPECT_LT(worst, 1e-9);
  // omega0 / omega_n
  EXPECT_NEAR(max_theta, 0.5 / std::sqrt(kStiffness / 1.7), 1e-4);
}

TEST(PneumaticChambers, ClosedValveEnergyIsConservedWithoutLeakage) {
  // The linearised chambers exchange exactly alpha dp omega with the load.
  PneumaticRotaryParams p = bare_params();
  p.flow_pressure_coefficient = 0.0;
  PneumaticRotaryPlant plant(p);
  PneumaticRotaryState s;
  s.omega = 0.8;
  plant.set_state(s);
  const double e0 = plant.stored_energy();
  double worst = 0.0;
  run(plant, 0.0, 5.0, [&](double, const PneumaticRotaryPlant& q) {
    worst = std::max(worst, std::abs(q.stored_energy() / e0 - 1.0));
  });
  std::printf("  E0 = %.4f J, worst drift %.2e\n", e0, worst);
  EXPECT_NEAR(e0, 0.5 * 1.7 * 0.8 * 0.8, 1e-12);
  EXPECT_LT(worst, 1e-8);
}

void expect_free_oscillation(double inertia, double c2, double f_expected, double zeta_expected) {
  PneumaticRotaryParams p = bare_params();
  p.inertia = inertia;
  p.flow_pressure_coefficient = c2;
  const Crossings c = free_oscillation(p, 0.2, 6.0);
  ASSERT_GE(c.down.size(), 5u);
  const double period = (c.down.back() - c.down.front()) / (c.down.size() - 1);
  // Logarithmic decrement of successive peaks of omega (exactly a damped
  // second-order response: I w'' + I (1/tau) w' + K w = 0).
  const double delta = std::log(c.peaks[1] / c.peaks[3]) / 2.0;
  const double zeta = delta / std::sqrt(4.0 * kPi * kPi + delta * delta);
  std::printf("  I = %.1f, C2 = %.1e: f = %.4f Hz (expected %.4f), zeta = %.4f (expected %.4f)\n", inertia, c2,
              1.0 / period, f_expected, zeta, zeta_expected);
  EXPECT_NEAR(1.0 / period, f_expected, 0.002 * f_expected);
  EXPECT_NEAR(zeta, zeta_expected, 0.002);
}

TEST(PneumaticChambers, NaturalFrequencyAndDampingMatchHandCalculation) {
  // Undamped (C2 = 0): f = sqrt(K / I) / 2 pi: 1.04 Hz at 1.7 kg m^2, 2.14 Hz at 0.4.
  const double wn17 = std::sqrt(kStiffness / 1.7), wn04 = std::sqrt(kStiffness / 0.4);
  EXPECT_NEAR(wn17 / (2 * kPi), 1.04, 0.005);
  EXPECT_NEAR(wn04 / (2 * kPi), 2.14, 0.005);
  expect_free_oscillation(1.7, 0.0, wn17 / (2 * kPi), 0.0);
  expect_free_oscillation(0.4, 0.0, wn04 / (2 * kPi), 0.0);
  // With the valve leakage C2 the chambers add damping 1/(2 tau):
  // zeta = 1 / (2 tau wn) = 0.14 and 0.07, damped frequency sqrt(wn^2 - 1/(4 tau^2)).
  const double s = 1.0 / (2.0 * kTau);
  expect_free_oscillation(1.7, 4e-9, std::sqrt(wn17 * wn17 - s * s) / (2 * kPi), s / wn17);
  expect_free_oscillation(0.4, 4e-9, std::sqrt(wn04 * wn04 - s * s) / (2 * kPi), s / wn04);
  EXPECT_NEAR(s / wn17, 0.14, 0.005);
  EXPECT_NEAR(s / wn04, 0.07, 0.005);
}

TEST(PneumaticChambers, OpenSpoolOnAFreeLoadGivesConstantSpeed) {
  // Steady state with the load free: dp = 0 (no torque), so the flow
  // 2 C1 x balances the volume change: 2 C1 x = 2 Pq alpha omega / (R T),
  // omega = C1 x R T / (Pq alpha): 0.376 rad/s per volt. The pneumatic servo
  // is a velocity source, which is why a P position loop is type 1.
  PneumaticRotaryPlant plant{bare_params()};
  const double u = 0.2;
  run(plant, u, 10.0);
  const double expected = 1.5 * 0.161e-3 * u * 287.0 * 293.0 / (4.5e5 * 1.2e-4);
  const auto m = measured(plant);
  std::printf("  omega = %.5f rad/s (expected %.5f), dp = %.1f Pa\n", m[sig::kOmega], expected, m[sig::kDp]);
  EXPECT_NEAR(m[sig::kOmega], expected, 1e-3 * expected);
  EXPECT_NEAR(m[sig::kDp], 0.0, 20.0);
}

TEST(PneumaticValve, DitherIs50HzAtTheConfiguredAmplitudeInTheSpool) {
  PneumaticRotaryParams p = bare_params();
  p.dither = true;
  PneumaticRotaryPlant plant(p);
  // Sample the spool every 0.25 ms for 1 s; project onto 50 Hz and 100 Hz.
  const double h = 0.25e-3;
  double c50 = 0.0, s50 = 0.0, c100 = 0.0, s100 = 0.0, hi = -1.0, lo = 1.0;
  int n = 0;
  run(plant, 0.0, 1.0, [&](double t, const PneumaticRotaryPlant& q) {
    const double x = measured(q)[sig::kSimX];
    hi = std::max(hi, x);
    lo = std::min(lo, x);
    c50 += x * std::cos(2 * kPi * 50 * t);
    s50 += x * std::sin(2 * kPi * 50 * t);
    c100 += x * std::cos(2 * kPi * 100 * t);
    s100 += x * std::sin(2 * kPi * 100 * t);
    ++n;
  }, h);
  const double a50 = 2.0 * std::hypot(c50, s50) / n, a100 = 2.0 * std::hypot(c100, s100) / n;
  const double expected = 0.161e-3 * 1.5;  // k_sol x 1.5 V = 0.24 mm
  std::printf("  50 Hz amplitude %.4e m (expected %.4e), 100 Hz %.1e, peak %.4e / %.4e\n", a50, expected, a100, hi, lo);
  EXPECT_NEAR(a50, expected, 1e-3 * expected);
  EXPECT_LT(a100, 1e-6 * expected);
  EXPECT_NEAR(hi, expected, 1e-9);
  EXPECT_NEAR(lo, -expected, 1e-9);
  EXPECT_GT(s50, 0.0);  // sine phase: starts at 0 going up
  EXPECT_NEAR(c50 / n, 0.0, 1e-3 * expected);

  // At the spool limit the dither is clipped: +5 V + 1.5 V exceeds 0.81 mm.
  plant.reset();
  run(plant, 5.0, 0.1, [&](double, const PneumaticRotaryPlant& q) {
    ASSERT_LE(measured(q)[sig::kSimX], 0.81e-3);
  }, h);
  EXPECT_EQ(plant.spool_position(5.0, 0.005), 0.81e-3);
  EXPECT_NEAR(plant.spool_position(5.0, 0.015), 0.161e-3 * 3.5, 1e-12);
}

TEST(PneumaticValve, NullOffsetShiftsTheCommand) {
  PneumaticRotaryParams p = bare_params();
  p.valve_null_offset = 0.3;
  PneumaticRotaryPlant plant(p);
  EXPECT_NEAR(plant.spool_position(0.0, 0.0), 0.161e-3 * 0.3, 1e-15);
  EXPECT_NEAR(plant.spool_position(-0.3, 0.0), 0.0, 1e-15);
}

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

// ------------------------------------------------------------- numerics

// Relay-driven stick/slip run with dither, hysteresis and brake: every
// discontinuity the integrator has to handle.
std::vector<double> hybrid_run(int substeps) {
  PneumaticRotaryParams p;
  p.brake.enabled = true;
  p.brake.level = 0.04;
  p.substeps = substeps;
  PneumaticRotaryPlant plant(p);
  std::vector<double> theta;
  double u = 1.5;
  for (int i = 0; i < 2400; ++i) {  // 6 s
    plant.advance({&u, 1}, kDt);
    const double th = plant.state().theta;
    if (th > 0.15) u = -1.5;
    if (th < -0.15) u = 1.5;
    theta.push_back(th);
  }
  return theta;
}

TEST(PneumaticNumerics, SubStepConvergence) {
  const auto a = hybrid_run(10), b = hybrid_run(20), c = hybrid_run(40);
  double d_ab = 0.0, d_bc = 0.0, range = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d_ab = std::max(d_ab, std::abs(a[i] - b[i]));
    d_bc = std::max(d_bc, std::abs(b[i] - c[i]));
    range = std::max(range, std::abs(a[i]));
  }
  std::printf("  max |theta_10 - theta_20| = %.2e rad, |theta_20 - theta_40| = %.2e rad (range %.3f rad)\n", d_ab,
              d_bc, range);
  EXPECT_GT(range, 0.1);
  // 10 sub-steps (the default, 0.25 ms) are within 1 urad (1/500 of the
  // 12-bit angle LSB) of 20 sub-steps. Rounding the stop/reversal to the
  // sub-step end instead of locating it gives 4e-5 rad here.
  EXPECT_LT(d_ab, 1e-6);
  EXPECT_LT(d_bc, d_ab);
}

TEST(PneumaticNumerics, SetStateWithVelocityCannotBeStuck) {
  PneumaticRotaryPlant plant{PneumaticRotaryParams{}};
  PneumaticRotaryState s;
  s.omega = -0.1;
  s.mode = RotaryLoadMode::kStuck;
  plant.set_state(s);
  EXPECT_EQ(plant.state().mode, RotaryLoadMode::kSlidingNegative);
}

TEST(PneumaticNumerics, EndStopHoldsTheArmNearTheLimit) {
  PneumaticRotaryPlant plant{bare_params()};
  run(plant, 5.0, 8.0);  // 1.9 rad/s open loop, into the +1 rad stop
  const auto s = plant.state();
  // Stall torque alpha 2 C1 x / C2 = 73 N m against 5000 N m/rad: 15 mrad in.
  std::printf("  theta at the stop %.4f rad\n", s.theta);
  EXPECT_GT(s.theta, 1.0);
  EXPECT_LT(s.theta, 1.03);
  EXPECT_NEAR(s.omega, 0.0, 1e-3);
}

}  // namespace
}  // namespace rigctl
