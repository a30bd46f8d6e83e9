// The quarter car's sub-step count follows its parameters: as few RK4
// sub-steps as the stiffest mode allows, accurate to well under 1 um on x_r
// against a converged run (200 sub-steps), and more sub-steps where the oil
// column is stiffer, where the nominal count would go unstable.
#include "plant/quarter_car/quarter_car_step_size.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "plant/quarter_car/quarter_car_plant.hpp"

namespace rigctl {
namespace {

constexpr double kPeriod = 0.0025;  // the loop's control period [s]

// x_b over 4 s of a slow sine command with the body bearing's stick-slip:
// the body sticks and breaks loose at every reversal.
std::vector<double> stick_slip_run(QuarterCarParams p, int substeps) {
  p.substeps = substeps;
  p.bearing_friction.enabled = true;
  QuarterCarPlant plant(p);
  std::vector<double> x;
  for (int k = 0; k < 1600; ++k) {
    const double u = 0.15 * std::sin(2.0 * std::numbers::pi * 1.5 * k * kPeriod);
    plant.advance({&u, 1}, kPeriod);
    x.push_back(plant.state().x_b);
  }
  return x;
}

// x_r over 2 s of a square-wave valve command (full reversals excite the
// hydraulic mode), one value per period. Non-finite values end the run early.
std::vector<double> square_wave_run(QuarterCarParams p, int substeps) {
  p.substeps = substeps;
  QuarterCarPlant plant(p);
  std::vector<double> x;
  for (int k = 0; k < 800; ++k) {
    const double u = (k / 100) % 2 == 0 ? 0.4 : -0.4;  // reverses every 0.25 s
    plant.advance({&u, 1}, kPeriod);
    x.push_back(plant.state().x_r);
    if (!std::isfinite(x.back())) break;
  }
  return x;
}

double max_difference(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return INFINITY;
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return std::isfinite(worst) ? worst : INFINITY;
}

// A much stiffer actuator: oil four times as stiff (a stiffer oil and a
// shorter cylinder have the same effect), half the dead volumes.
QuarterCarParams stiff() {
  QuarterCarParams p;
  p.bulk_modulus *= 4.0;
  p.dead_volume_cap *= 0.5;
  p.dead_volume_rod *= 0.5;
  return p;
}

TEST(QuarterCarStepSize, BoundCoversTheMidStrokeHydraulicMode) {
  const QuarterCarParams p;
  // Mid-stroke oil-column stiffness on the rod, by hand: beta (A1^2/V1 + A2^2/V2).
  const double mid = 0.5 * (p.stroke_max - p.stroke_min);
  const double v1 = p.dead_volume_cap + p.area_cap * mid, v2 = p.dead_volume_rod + p.area_rod * mid;
  const double k = p.bulk_modulus * (p.area_cap * p.area_cap / v1 + p.area_rod * p.area_rod / v2) + p.tyre_stiffness;
  const double mid_rate = std::sqrt(k / p.mass_rod);
  EXPECT_GT(quarter_car_fastest_rate(p), mid_rate);
  const int n = quarter_car_substeps(p, kPeriod);
  EXPECT_LE(kPeriod / n * quarter_car_fastest_rate(p), kQuarterCarStepLimit);
  EXPECT_GT(kPeriod / (n - 1) * quarter_car_fastest_rate(p), kQuarterCarStepLimit);  // and no more than needed
}

TEST(QuarterCarStepSize, AnExplicitCountIsKept) {
  QuarterCarParams p;
  p.substeps = 13;
  EXPECT_EQ(quarter_car_substeps(p, kPeriod), 13);
}

TEST(QuarterCarStepSize, AutomaticCountAgreesWithAConvergedRunToWellUnderAMicrometre) {
  const QuarterCarParams p;
  const int n = quarter_car_substeps(p, kPeriod);
  const double error = max_difference(square_wave_run(p, 0), square_wave_run(p, 200));
  std::printf("nominal: %d sub-steps, max |x_r - converged| = %.3g m\n", n, error);
  EXPECT_LT(error, 1e-6);  // 1 um: far below the rig's sensor resolution
}

TEST(QuarterCarStepSize, StifferOilGetsMoreSubStepsAndStaysAccurate) {
  const QuarterCarParams nominal;
  const QuarterCarParams p = stiff();
  const int n_nominal = quarter_car_substeps(nominal, kPeriod);
  const int n_stiff = quarter_car_substeps(p, kPeriod);
  EXPECT_GT(n_stiff, n_nominal);
  const std::vector<double> converged = square_wave_run(p, 200);
  const double automatic = max_difference(square_wave_run(p, 0), converged);
  const double at_nominal_count = max_difference(square_wave_run(p, n_nominal), converged);
  std::printf("stiff: %d sub-steps error %.3g m; the nominal %d sub-steps error %.3g m\n", n_stiff, automatic, n_nominal,
              at_nominal_count);
  EXPECT_LT(automatic, 1e-6);
  EXPECT_GT(at_nominal_count, 1e-3);  // unstable: why the count must follow the parameters
}

TEST(QuarterCarStepSize, StickSlipOfTheBodyBearingStaysAccurate) {
  const QuarterCarParams p;
  const double automatic = max_difference(stick_slip_run(p, 0), stick_slip_run(p, 200));
  const double old_fixed = max_difference(stick_slip_run(p, 20), stick_slip_run(p, 200));
  std::printf("stick-slip: max |x_b - converged| %.3g m automatic, %.3g m at 20 sub-steps\n", automatic, old_fixed);
  EXPECT_LT(automatic, 1e-6);
}

}  // namespace
}  // namespace rigctl
