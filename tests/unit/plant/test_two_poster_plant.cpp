// The half car on two hydraulic posts (plant/two_poster): at rest it stays
// at rest, a step on one post moves that post and, through the body's pitch
// and heave, both ends of the body, and a seal-wear leak costs the valve
// command that the rest then needs.
#include <gtest/gtest.h>

#include <cmath>

#include "plant/two_poster/two_poster_plant.hpp"
#include "two_poster_loops.hpp"

namespace rigctl {
namespace {

namespace sig = two_poster_signal;

std::array<double, sig::kCount> measured(const TwoPosterPlant& plant) {
  std::array<double, sig::kCount> y{};
  plant.measure(y);
  return y;
}

TEST(TwoPosterPlant, RestsAtHomeUnderItsRestCommands) {
  TwoPosterPlant plant(TwoPosterParams{});
  const std::array<double, 2> u{plant.rest_command(0), plant.rest_command(1)};
  for (int i = 0; i < 800; ++i) plant.advance(u, 0.0025);  // 2 s
  const auto y = measured(plant);
  for (std::size_t c : {sig::kZr1, sig::kZr2, sig::kZu1, sig::kZu2, sig::kZs}) EXPECT_NEAR(y[c], 0.0, 1e-6) << c;
  EXPECT_NEAR(y[sig::kPhi], 0.0, 1e-6);
  // The posts carry their axles: p1 A1 - p2 A2 = the static load.
  const auto& post = plant.params().posts[0];
  EXPECT_NEAR(y[sig::kP1a] * post.area_cap - y[sig::kP2a] * post.area_rod, plant.static_load(0), 1.0);
}

TEST(TwoPosterPlant, OnePostsStepMovesBothEndsOfTheBodyOnItsWay) {
  TwoPosterPlant plant(TwoPosterParams{});
  test::TwoPosterLoops loops;
  std::vector<std::vector<double>> demands{std::vector<double>(2400, 0.005), std::vector<double>(2400, 0.0)};
  const double a = plant.params().car.dist_front, b = plant.params().car.dist_rear;
  const auto r = loops.play(plant, demands, [&](const auto& y) {
    return std::vector<double>{y[sig::kZr1], y[sig::kZr2], y[sig::kZs] + a * y[sig::kPhi], y[sig::kZs] - b * y[sig::kPhi]};
  });
  EXPECT_NEAR(r[0].back(), 0.005, 1e-4);  // the stepped post reaches its demand in 6 s
  EXPECT_NEAR(r[1].back(), 0.0, 1e-4);    // the other holds home
  double rear_peak = 0.0;
  for (double v : r[3]) rear_peak = std::max(rear_peak, std::abs(v));
  EXPECT_GT(rear_peak, 2e-4) << "the rear of the body moves when the front post steps";
  EXPECT_NEAR(r[2].back(), 0.005, 1e-3);  // the body settles on its springs over the stepped axle
}

TEST(TwoPosterPlant, ASealWearLeakNeedsMoreValveToHoldHome) {
  TwoPosterParams worn;
  worn.posts[1].extra_laminar_leak = 2e-12;  // [m^3/s/Pa]: doubles the nominal cross-port conductance (1 / 2.45e11 = 4.1e-12)
  const TwoPosterPlant nominal_plant(TwoPosterParams{}), worn_plant(worn);
  EXPECT_NEAR(worn_plant.rest_command(0), nominal_plant.rest_command(0), 1e-12);
  EXPECT_GT(std::abs(worn_plant.rest_command(1)), 1.3 * std::abs(nominal_plant.rest_command(1)));
}

}  // namespace
}  // namespace rigctl
