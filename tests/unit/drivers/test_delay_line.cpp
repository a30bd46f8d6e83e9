#include <gtest/gtest.h>

#include <cmath>

#include "drivers/sim/delay_line.hpp"

namespace rigctl {

TEST(DelayLine, SlowSineComesOutLateByTheFractionalDelay) {
  const double dt = 0.0025, tau = 0.0037;  // 1.48 samples: not a whole number
  DelayLine line(tau, dt);
  const double w = 2.0 * M_PI * 2.0;
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * dt;
    const double y = line.push(std::sin(w * t));
    if (t > 0.05) worst = std::max(worst, std::abs(y - std::sin(w * (t - tau))));
  }
  // Cubic interpolation of a 2 Hz sine sampled at 400 Hz: error ~ (w dt)^4 / 16.
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(worst, 0.0);
}

TEST(DelayLine, StepArrivesAfterTheDelayAndTheStartHoldsTheFirstValue) {
  DelayLine line(0.010, 0.0025);  // 4 samples
  EXPECT_DOUBLE_EQ(line.push(3.0), 3.0);
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(line.push(3.0), 3.0);
  EXPECT_DOUBLE_EQ(line.push(5.0), 3.0);
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(line.push(5.0), 3.0);
  EXPECT_DOUBLE_EQ(line.push(5.0), 5.0);
}

TEST(DelayLine, ZeroDelayIsInactive) {
  EXPECT_FALSE(DelayLine(0.0, 0.0025).active());
  EXPECT_TRUE(DelayLine(0.001, 0.0025).active());
}

}  // namespace rigctl
