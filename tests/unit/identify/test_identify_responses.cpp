// `rigctl identify --response NAME`: further response channels after the
// controller's own, and the quarter car's linearisation of them.
#include <gtest/gtest.h>

#include <cmath>

#include "config/rig_config.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/identify/plant_linearisation.hpp"

namespace rigctl {
namespace {

RigConfig quarter_car() { return load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml"); }

TEST(IdentifyResponses, ExtraChannelsFollowTheControlledOneOnce) {
  IdentifySettings s;
  s.extra_responses = {"x_w", "x_r", "x_b"};  // x_r is the controller's own: not twice
  const IdentifyPlan plan = plan_identification(quarter_car(), s);
  EXPECT_EQ(plan.responses, (std::vector<std::string>{"x_r", "x_w", "x_b"}));
  EXPECT_EQ(plan_identification(quarter_car(), IdentifySettings{}).responses, (std::vector<std::string>{"x_r"}));
}

TEST(IdentifyResponses, TheLinearisationHasTheWheelAndTheBody) {
  const RigConfig c = quarter_car();
  const auto frf = sampled_frf(linearise_quarter_car(c.quarter_car, 0.08, {"x_r", "x_w", "x_b"}), c.loop.period_s, {0.5, 40.0});
  ASSERT_EQ(frf.size(), 3u);
  // With the body held on its bearing the wheel sits between the stiff tyre
  // and the soft spring and follows the rod (kt / (kt + ks)), the body not at all.
  const auto& p = c.quarter_car;
  EXPECT_NEAR(std::abs(frf[1].value[0] / frf[0].value[0]), p.tyre_stiffness / (p.tyre_stiffness + p.spring_stiffness), 0.01);
  EXPECT_LT(std::abs(frf[2].value[0] / frf[0].value[0]), 1e-3);
  EXPECT_THROW(linearise_quarter_car(c.quarter_car, 0.08, {"theta"}), std::invalid_argument);
}

}  // namespace
}  // namespace rigctl
