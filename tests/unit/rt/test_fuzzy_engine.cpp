// The Mamdani engine on small cases computed by hand, the paper's
// membership functions and 27-rule table (seed 001), and the fuzzy
// suspension controller's signs and allocation-free update.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "rt/control/fuzzy_engine.hpp"
#include "rt/control/fuzzy_suspension_controller.hpp"
#include "rt/control/lqr_controller.hpp"
#include "rt/control/skyhook_controller.hpp"
#include "allocation_counter.hpp"

using namespace rigctl;


namespace {

MembershipFunctionSpec tri(const char* name, double a, double b, double c) {
  return {name, MembershipShape::kTriangle, {a, b, c}};
}
MembershipFunctionSpec trap(const char* name, double a, double b, double c, double d) {
  return {name, MembershipShape::kTrapezoid, {a, b, c, d}};
}

// Two inputs, two rules, output sets L = tri(0, 1, 2) and H = tri(2, 3, 4)
// on [0, 4]:
//   rule 1: IF x is A AND y is C THEN out is L
//   rule 2: IF x is B AND y is D THEN out is H
FuzzyEngineSpec two_rule_spec() {
  FuzzyEngineSpec s;
  s.inputs.push_back({"x", 0.0, 3.0, 1.0, {tri("A", 0.0, 1.0, 2.0), tri("B", 1.0, 2.0, 3.0)}});
  s.inputs.push_back({"y", 0.0, 2.0, 1.0, {trap("C", 0.0, 0.0, 0.5, 1.5), trap("D", 0.5, 1.5, 2.0, 2.0)}});
  s.output = {"out", 0.0, 4.0, 1.0, {tri("L", 0.0, 1.0, 2.0), tri("H", 2.0, 3.0, 4.0)}};
  s.rules = {{{"A", "C"}, "L", 1.0}, {{"B", "D"}, "H", 1.0}};
  s.resolution = 4001;
  return s;
}

}  // namespace

// ---------------------------------------------------------------- memberships

TEST(FuzzyEngine, MembershipFunctionsAtHandPickedPoints) {
  const MembershipFunction t = MembershipFunction::from_spec(tri("t", -0.2, 0.0, 0.2));
  EXPECT_DOUBLE_EQ(t(0.0), 1.0);
  EXPECT_DOUBLE_EQ(t(0.1), 0.5);
  EXPECT_NEAR(t(-0.15), 0.25, 1e-15);
  EXPECT_DOUBLE_EQ(t(0.2), 0.0);
  EXPECT_DOUBLE_EQ(t(-0.2), 0.0);
  EXPECT_DOUBLE_EQ(t(0.3), 0.0);
  const MembershipFunction z = MembershipFunction::from_spec(trap("z", 1.0, 2.0, 4.0, 7.0));
  EXPECT_DOUBLE_EQ(z(1.5), 0.5);
  EXPECT_DOUBLE_EQ(z(2.0), 1.0);
  EXPECT_DOUBLE_EQ(z(3.0), 1.0);
  EXPECT_DOUBLE_EQ(z(4.0), 1.0);
  EXPECT_DOUBLE_EQ(z(5.5), 0.5);
  EXPECT_NEAR(z(6.4), 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(z(7.0), 0.0);
  // Shoulder: a vertical left flank belongs to the set.
  const MembershipFunction s = MembershipFunction::from_spec(trap("s", -1.0, -1.0, -0.8, -0.6));
  EXPECT_DOUBLE_EQ(s(-1.0), 1.0);
  EXPECT_DOUBLE_EQ(s(-0.9), 1.0);
  EXPECT_NEAR(s(-0.7), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(s(-0.6), 0.0);
  EXPECT_DOUBLE_EQ(s(-1.01), 0.0);
  EXPECT_THROW(MembershipFunction::from_spec(tri("bad", 0.0, 1.0, 0.5)), std::invalid_argument);
  EXPECT_THROW(MembershipFunction::from_spec({"bad", MembershipShape::kTrapezoid, {0.0, 1.0, 2.0}}), std::invalid_argument);
}

TEST(FuzzyEngine, PaperMembershipFunctionsAsChosen) {
  FuzzyEngine e(paper_fuzzy_spec());
  // Input 1: NVL trapezoid (-1, -1, -0.8, -0.6), NL triangle (-0.8, -0.6, -0.4) ... PVL.
  EXPECT_DOUBLE_EQ(e.membership(0, 0, -0.9), 1.0);
  EXPECT_NEAR(e.membership(0, 0, -0.7), 0.5, 1e-12);
  EXPECT_NEAR(e.membership(0, 1, -0.7), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(e.membership(0, 4, 0.0), 1.0);   // ZE
  EXPECT_NEAR(e.membership(0, 5, 0.05), 0.25, 1e-12);  // PS at 0.05
  EXPECT_NEAR(e.membership(0, 4, 0.05), 0.75, 1e-12);  // ZE at 0.05
  EXPECT_DOUBLE_EQ(e.membership(0, 8, 1.0), 1.0);   // PVL
  // Input 2: N (-1, -1, -0.5, 0), ZE (-0.5, 0, 0.5), P (0, 0.5, 1, 1).
  EXPECT_DOUBLE_EQ(e.membership(1, 0, -0.25), 0.5);
  EXPECT_DOUBLE_EQ(e.membership(1, 1, -0.25), 0.5);
  EXPECT_DOUBLE_EQ(e.membership(1, 2, 0.75), 1.0);
  // Every point of each universe has total membership 1 (partitions of unity).
  for (double x = -1.0; x <= 1.0; x += 0.0137) {
    double sum1 = 0.0, sum2 = 0.0;
    for (std::size_t s = 0; s < 9; ++s) sum1 += e.membership(0, s, x);
    for (std::size_t s = 0; s < 3; ++s) sum2 += e.membership(1, s, x);
    EXPECT_NEAR(sum1, 1.0, 1e-12) << x;
    EXPECT_NEAR(sum2, 1.0, 1e-12) << x;
  }
  // Input scaling: physical 0.05 m/s -> 0.5 with the default 0.1 m/s range;
  // beyond the range the input saturates in the outermost set.
  const std::array<double, 2> in{0.05, 0.0};
  e.evaluate(in);
  EXPECT_DOUBLE_EQ(e.input_universe(0), 0.5);
  const std::array<double, 2> far{-7.0, 0.0};
  e.evaluate(far);
  EXPECT_DOUBLE_EQ(e.input_universe(0), -1.0);
  EXPECT_DOUBLE_EQ(e.input_membership(0, 0), 1.0);
}

// --------------------------------------------------------------------- rules

TEST(FuzzyEngine, RuleFiringStrengthsOnATwoRuleCase) {
  FuzzyEngine e(two_rule_spec());
  // x = 1.25: A 0.75, B 0.25. y = 1.2: C (1.5 - 1.2)/1 = 0.3, D (1.2 - 0.5)/1 = 0.7.
  const std::array<double, 2> in{1.25, 1.2};
  e.evaluate(in);
  EXPECT_DOUBLE_EQ(e.input_membership(0, 0), 0.75);
  EXPECT_DOUBLE_EQ(e.input_membership(0, 1), 0.25);
  EXPECT_NEAR(e.input_membership(1, 0), 0.3, 1e-15);
  EXPECT_NEAR(e.input_membership(1, 1), 0.7, 1e-15);
  EXPECT_NEAR(e.rule_strength(0), 0.3, 1e-15);   // min(0.75, 0.3)
  EXPECT_NEAR(e.rule_strength(1), 0.25, 1e-15);  // min(0.25, 0.7)
  EXPECT_NEAR(e.output_level(0), 0.3, 1e-15);
  EXPECT_NEAR(e.output_level(1), 0.25, 1e-15);
}

TEST(FuzzyEngine, CentroidOfClippedSetsByHand) {
  FuzzyEngine e(two_rule_spec());
  // x = 0.6: A 0.6, B 0. y = 0.2: C 1, D 0 -> only rule 1, L clipped at 0.6:
  // a symmetric trapezoid about 1 -> centroid 1.
  const std::array<double, 2> one{0.6, 0.2};
  EXPECT_NEAR(e.evaluate(one), 1.0, 1e-9);
  // x = 1.2: A 0.8, B 0.2; y = 0.9: C 0.6, D 0.4 -> rule 1 at 0.6 (L),
  // rule 2 at 0.2 (H). L clipped at 0.6: area 0.6 (2 + 0.8)/2 = 0.84 at 1;
  // H clipped at 0.2: area 0.2 (2 + 1.6)/2 = 0.36 at 3.
  // Centroid (0.84 * 1 + 0.36 * 3) / 1.2 = 1.6.
  const std::array<double, 2> two{1.2, 0.9};
  e.evaluate(two);
  EXPECT_NEAR(e.rule_strength(0), 0.6, 1e-12);
  EXPECT_NEAR(e.rule_strength(1), 0.2, 1e-12);
  EXPECT_NEAR(e.last_output_universe(), 1.6, 1e-5);
  // Nothing fires (x = 3 is in neither A's nor B's support... B is 0 at 3): middle of the universe.
  const std::array<double, 2> none{3.0, 0.2};
  EXPECT_NEAR(e.evaluate(none), 2.0, 1e-12);

  // An asymmetric set: right triangle (0, 0, 0, 3) clipped at 0.5 is flat
  // on [0, 1.5] and falls to 0 at 3: area 0.75 + 0.375, moment
  // 0.5 * 1.5^2 / 2 + 0.375 * 2 -> centroid 1.3125 / 1.125 = 7/6.
  FuzzyEngineSpec s;
  s.inputs.push_back({"x", 0.0, 1.0, 1.0, {tri("half", -1.0, 0.0, 1.0)}});
  s.output = {"out", 0.0, 3.0, 10.0, {trap("R", 0.0, 0.0, 0.0, 3.0)}};
  s.rules = {{{"half"}, "R", 1.0}};
  s.resolution = 3001;
  FuzzyEngine r(s);
  const std::array<double, 1> x{0.5};
  EXPECT_NEAR(r.evaluate(x), 10.0 * 7.0 / 6.0, 1e-5);  // output scale 10
  EXPECT_NEAR(r.last_output_universe(), 7.0 / 6.0, 1e-6);
}

TEST(FuzzyEngine, RuleWeightsAndDontCareAntecedents) {
  FuzzyEngineSpec s = two_rule_spec();
  s.rules = {{{"A", "any"}, "L", 0.5}, {{"", "D"}, "H", 1.0}};
  FuzzyEngine e(s);
  const std::array<double, 2> in{1.25, 1.2};
  e.evaluate(in);
  EXPECT_NEAR(e.rule_strength(0), 0.5 * 0.75, 1e-15);  // y ignored, weight 0.5
  EXPECT_NEAR(e.rule_strength(1), 0.7, 1e-15);         // x ignored
}

TEST(FuzzyEngine, BadSpecsAreRejectedWithTheReason) {
  auto error_of = [](FuzzyEngineSpec s) {
    try {
      FuzzyEngine e(s);
    } catch (const std::invalid_argument& ex) {
      return std::string(ex.what());
    }
    return std::string("<no exception>");
  };
  FuzzyEngineSpec s = two_rule_spec();
  s.rules[1].consequent = "HUGE";
  EXPECT_NE(error_of(s).find("no set HUGE"), std::string::npos) << error_of(s);
  s = two_rule_spec();
  s.rules[0].antecedents = {"A"};
  EXPECT_NE(error_of(s).find("rule 1"), std::string::npos) << error_of(s);
  s = two_rule_spec();
  s.inputs[0].max = s.inputs[0].min;
  EXPECT_NE(error_of(s).find("min < max"), std::string::npos) << error_of(s);
  s = two_rule_spec();
  s.resolution = 2;
  EXPECT_NE(error_of(s).find("resolution"), std::string::npos) << error_of(s);
  s = two_rule_spec();
  s.inputs[1].sets[1].name = "C";
  EXPECT_NE(error_of(s).find("twice"), std::string::npos) << error_of(s);
}

// --------------------------------------------------------------- paper table

TEST(FuzzyEngine, PaperTableHasTwentySevenRulesCoveringNineByThree) {
  const FuzzyEngineSpec spec = paper_fuzzy_spec();
  ASSERT_EQ(spec.inputs.size(), 2u);
  EXPECT_EQ(spec.inputs[0].sets.size(), 9u);
  EXPECT_EQ(spec.inputs[1].sets.size(), 3u);
  EXPECT_EQ(spec.output.sets.size(), 9u);
  ASSERT_EQ(spec.rules.size(), 27u);
  std::set<std::pair<std::string, std::string>> seen;
  for (const auto& r : spec.rules) seen.insert({r.antecedents[0], r.antecedents[1]});
  EXPECT_EQ(seen.size(), 27u);
  // The paper's two quoted rules, by its numbering.
  EXPECT_EQ(spec.rules[0].antecedents, (std::vector<std::string>{"NVL", "N"}));
  EXPECT_EQ(spec.rules[0].consequent, "NVL");
  EXPECT_EQ(spec.rules[14].antecedents, (std::vector<std::string>{"PS", "ZE"}));
  EXPECT_EQ(spec.rules[14].consequent, "PS");
  // The ZE column is the identity; ZE row gives ZE.
  for (const auto& r : spec.rules) {
    if (r.antecedents[1] == "ZE") {
      EXPECT_EQ(r.consequent, r.antecedents[0]);
    }
    if (r.antecedents[0] == "ZE") {
      EXPECT_EQ(r.consequent, "ZE");
    }
  }
}

TEST(FuzzyEngine, PaperTableIsOddInTheFirstInputButNotUnderNegatingBoth) {
  FuzzyEngine e(paper_fuzzy_spec({1.0, 1.0, 1.0}));
  double worst_joint = 0.0;
  for (double x1 = -1.0; x1 <= 1.0001; x1 += 0.05) {
    for (double x2 = -1.0; x2 <= 1.0001; x2 += 0.05) {
      const std::array<double, 2> a{x1, x2}, b{-x1, x2}, c{-x1, -x2};
      const double f = e.evaluate(a);
      EXPECT_NEAR(e.evaluate(b), -f, 1e-9) << x1 << " " << x2;
      worst_joint = std::max(worst_joint, std::abs(e.evaluate(c) + f));
    }
  }
  // As printed, N enlarges and P shrinks |f| whatever the sign of x1: e.g.
  // (PS, N) -> PM but (NS, P) -> NS.
  std::printf("printed table: largest |f(-x1,-x2) + f(x1,x2)| = %.3f of the output range\n", worst_joint);
  EXPECT_GT(worst_joint, 0.1);
  const std::array<double, 2> ps_n{0.2, -0.9}, ns_p{-0.2, 0.9};
  EXPECT_GT(e.evaluate(ps_n), 0.3);
  EXPECT_NEAR(e.evaluate(ns_p), -0.2, 0.02);
}

TEST(FuzzyEngine, OddSymmetricVariantNegatesTheOutputWhenBothInputsAreNegated) {
  FuzzyEngine e(paper_fuzzy_spec({1.0, 1.0, 1.0}, PaperRuleTable::kOddSymmetric));
  for (double x1 = -1.0; x1 <= 1.0001; x1 += 0.05) {
    for (double x2 = -1.0; x2 <= 1.0001; x2 += 0.05) {
      const std::array<double, 2> a{x1, x2}, c{-x1, -x2};
      EXPECT_NEAR(e.evaluate(c), -e.evaluate(a), 1e-9) << x1 << " " << x2;
    }
  }
  // Rows NVL..ZE are the printed ones.
  const auto printed = paper_fuzzy_spec();
  const auto odd = paper_fuzzy_spec({}, PaperRuleTable::kOddSymmetric);
  for (std::size_t r = 0; r < 27; ++r) {
    const auto& row = odd.rules[r].antecedents[0];
    if (row[0] == 'N' || row == "ZE") {
      EXPECT_EQ(odd.rules[r].consequent, printed.rules[r].consequent);
    }
  }
}

TEST(FuzzyEngine, PaperOutputIsScaledToTheForceLimitAndMonotoneInTheFirstInput) {
  FuzzyEngine e(paper_fuzzy_spec({0.1, 4.0, 2000.0}));
  // Full NVL alone: centroid of the trapezoid (-1, -1, -0.8, -0.6):
  // (0.2 * -0.9 + 0.1 * -0.7333) / 0.3 = -0.8444 -> -1689 N.
  const std::array<double, 2> full{-1.0, 0.0};
  EXPECT_NEAR(e.evaluate(full), 2000.0 * (0.2 * -0.9 + 0.1 * (-0.8 + 0.2 / 3.0)) / 0.3, 0.5);
  double last = -1e9;
  for (double v = -0.12; v <= 0.12; v += 0.001) {
    const std::array<double, 2> in{v, 0.0};
    const double f = e.evaluate(in);
    EXPECT_GE(f, last - 1e-9) << v;
    EXPECT_LE(std::abs(f), 2000.0);
    last = f;
  }
}

// ------------------------------------------------------ suspension controller

TEST(FuzzySuspensionController, OpposesBodyMotionAtEachCornerAndClamps) {
  FuzzySuspensionConfig cfg;
  cfg.force_limit = 1500.0;  // below the engine's 0.844 * 2000 N reach, so the clamp shows
  FuzzySuspensionController c(cfg);
  Sample s;
  // Body rising at the CG (0.03 m/s), no rotation: both corners push down.
  s.value[6] = 0.03;
  Command cmd;
  ControllerTerms t;
  c.update(0.0, s, cmd, t);
  EXPECT_LT(cmd.value[0], 0.0);
  EXPECT_LT(cmd.value[1], 0.0);
  EXPECT_NEAR(cmd.value[0], cmd.value[1], 1e-9);
  EXPECT_DOUBLE_EQ(t.term[2], -0.03);  // x1 at corner 1: velocity error
  // Nose pitching up (phi_dot > 0): front corner rises, rear falls.
  s.value[6] = 0.0;
  s.value[8] = 0.02;
  c.update(0.0, s, cmd, t);
  EXPECT_LT(cmd.value[0], 0.0);
  EXPECT_GT(cmd.value[1], 0.0);
  // Far beyond the range: clamped to the limit.
  s.value[8] = 0.0;
  s.value[6] = -1.0;
  c.update(0.0, s, cmd, t);
  EXPECT_DOUBLE_EQ(cmd.value[0], 1500.0);
  EXPECT_DOUBLE_EQ(cmd.value[1], 1500.0);
  EXPECT_TRUE(t.saturated);
  EXPECT_EQ(c.term_names().size(), 6u);
}

TEST(FuzzySuspensionController, DisplacementInputUsesTheSetpoint) {
  FuzzySuspensionConfig cfg;
  cfg.first_input = FuzzyFirstInput::kDisplacement;
  cfg.engine = paper_fuzzy_spec({0.01, 4.0, 2000.0});  // 10 mm to the universe edge
  FuzzySuspensionController c(cfg);
  Sample s;
  s.value[2] = 0.004;   // z_s
  s.value[3] = 0.001;   // phi: front corner 0.004 + 1.524e-3, rear 0.004 - 1.156e-3
  Command cmd;
  ControllerTerms t;
  c.update(0.002, s, cmd, t);
  EXPECT_NEAR(t.term[2], 0.002 - (0.004 + 1.524e-3), 1e-15);
  EXPECT_NEAR(t.term[4], 0.002 - (0.004 - 1.156e-3), 1e-15);
  EXPECT_LT(cmd.value[0], cmd.value[1]);  // the front is further above the demand
  EXPECT_LT(cmd.value[0], 0.0);
  EXPECT_DOUBLE_EQ(t.error, 0.002 - 0.004);
}

TEST(FuzzySuspensionController, UpdatesWithoutAllocating) {
  FuzzySuspensionController fuzzy{FuzzySuspensionConfig{}};
  SkyhookController sky{SkyhookConfig{}};
  LqrController lqr(LqrConfig::from_design(HalfCarParams{}));
  FuzzyEngine engine(paper_fuzzy_spec());
  Sample s;
  Command cmd;
  ControllerTerms t;
  const long before = rigctl::test::allocation_count();
  double sink = 0.0;
  for (int k = 0; k < 1000; ++k) {
    for (std::size_t i = 0; i < 12; ++i) s.value[i] = 0.01 * std::sin(0.1 * k + static_cast<double>(i));
    fuzzy.update(0.0, s, cmd, t);
    sink += cmd.value[0];
    sky.update(0.0, s, cmd, t);
    sink += cmd.value[0];
    lqr.update(0.0, s, cmd, t);
    sink += cmd.value[1];
    const std::array<double, 2> in{s.value[0], s.value[1]};
    sink += engine.evaluate(in);
  }
  EXPECT_EQ(rigctl::test::allocation_count(), before);
  EXPECT_TRUE(std::isfinite(sink));
}
