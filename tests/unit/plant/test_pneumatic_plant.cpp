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
#include "pneumatic_plant_stepping.hpp"

namespace rigctl {
namespace {

using namespace pneumatic_test;

constexpr double kPi = std::numbers::pi;

// Hand values from the nominal parameters (docs/rig-models.md 2.5).
constexpr double kGammaRT = 1.4 * 287.0 * 293.0;                  // gamma R T [J/kg]
constexpr double kTau = 0.25e-3 / (kGammaRT * 4e-9);              // V / (gamma R T C2) = 0.531 s
constexpr double kStiffness = 2.0 * 1.4 * 4.5e5 * 1.2e-4 * 1.2e-4 / 0.25e-3;  // 2 gamma Pq alpha^2 / V = 72.6 N m/rad

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
