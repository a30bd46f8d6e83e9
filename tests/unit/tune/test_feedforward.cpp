// The velocity feedforward `rigctl tune` designs: 1 / the plant's speed per
// command, read where the plant is an integrator, in the octave below the
// crossover; none where it would not mean anything.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "tools/tune/feedforward.hpp"

namespace rigctl {
namespace {

// A valve-controlled cylinder: K_v / s with a valve lag, and below 2 Hz a
// smaller speed per command (the leak and friction of a small excitation).
PlantResponse cylinder(double velocity_gain, double valve_tau_s) {
  PlantResponse p;
  for (double f = 0.5; f < 30.0; f += 1.0) {
    const std::complex<double> s(0.0, 2.0 * std::numbers::pi * f);
    const double small_motion = f < 2.0 ? 0.6 : 1.0;
    p.frequency_hz.push_back(f);
    p.position.push_back(small_motion * velocity_gain / (s * (1.0 + valve_tau_s * s)));
    p.coherence.push_back(0.99);
  }
  return p;
}

RigConfig quarter_car() { return parse_rig_config(test::shipped_config(), "quarter_car.yaml"); }

TEST(Feedforward, IsOneOverTheSpeedPerCommandBelowTheCrossover) {
  const FeedforwardDesign d = design_feedforward(cylinder(0.3, 0.001), 12.0, quarter_car());
  ASSERT_TRUE(d.reason_for_none.empty()) << d.reason_for_none;
  EXPECT_DOUBLE_EQ(d.band_low_hz, 6.0);
  EXPECT_DOUBLE_EQ(d.band_high_hz, 12.0);
  // The median of the lines 6.5-11.5 Hz: of 8.5 and 9.5 Hz, 0.3 / |1 + j w tau|.
  auto speed = [](double f) { return 0.3 / std::abs(1.0 + std::complex<double>(0.0, 2.0 * std::numbers::pi * f * 0.001)); };
  EXPECT_NEAR(d.velocity_gain, 0.5 * (speed(8.5) + speed(9.5)), 1e-12);
  EXPECT_NEAR(d.kff, 1.0 / d.velocity_gain, 1e-12);
}

TEST(Feedforward, LowCoherenceLinesAreNotUsed) {
  PlantResponse p = cylinder(0.3, 0.0);
  for (std::size_t i = 0; i < p.frequency_hz.size(); ++i) {
    if (p.frequency_hz[i] > 6.0 && p.frequency_hz[i] < 9.0) {
      p.position[i] *= 3.0;
      p.coherence[i] = 0.2;  // noise: not the plant
    }
  }
  EXPECT_NEAR(design_feedforward(p, 12.0, quarter_car()).velocity_gain, 0.3, 1e-9);
}

TEST(Feedforward, NoneWhereItWouldMeanNothingAndTheReasonIsSaid) {
  // A plant that does not integrate there (a spring-held one: phase near 0).
  PlantResponse spring = cylinder(0.3, 0.0);
  for (auto& g : spring.position) g = std::abs(g);
  FeedforwardDesign d = design_feedforward(spring, 12.0, quarter_car());
  EXPECT_EQ(d.kff, 0.0);
  EXPECT_NE(d.reason_for_none.find("not an integrator"), std::string::npos) << d.reason_for_none;
  // An unfiltered step: one tick of demand rate would open the valve fully.
  RigConfig unfiltered = quarter_car();
  unfiltered.profile.filter_tau_s = 0.0;
  d = design_feedforward(cylinder(0.3, 0.0), 12.0, unfiltered);
  EXPECT_EQ(d.kff, 0.0);
  EXPECT_NE(d.reason_for_none.find("unfiltered"), std::string::npos) << d.reason_for_none;
  // No crossover: no octave below it.
  EXPECT_EQ(design_feedforward(cylinder(0.3, 0.0), NAN, quarter_car()).kff, 0.0);
  // P+V+dP has no such path.
  const RigConfig pneumatic = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/pneumatic_rotary.yaml");
  EXPECT_NE(design_feedforward(cylinder(0.3, 0.0), 12.0, pneumatic).reason_for_none.find("only the PI"), std::string::npos);
}

}  // namespace
}  // namespace rigctl
