// The safety state machine: every allowed transition, every refused one with
// its reason, the edge-triggered reset, and a demand without jumps whenever
// the rig leaves or re-enters running.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "allocation_counter.hpp"
#include "rt/safety/rig_state_machine.hpp"

using namespace rigctl;
using K = OperatorCommandKind;
using S = SafetyState;

namespace {

constexpr double kT = 0.0025;

StateMachineConfig config() {
  StateMachineConfig c;
  c.period_s = kT;
  c.hold_deceleration = 1.0;  // [m/s^2]
  c.setpoint_rate = 0.05;     // [m/s]
  c.setpoint_min = -0.1;
  c.setpoint_max = 0.1;
  c.stop_timeout_s = 2.0;
  return c;
}

OperatorCommand cmd(K kind, double value = 0.0) { return OperatorCommand{kind, value, 0}; }

// One tick with quiet inputs: begin, then the demand.
double tick(RigStateMachine& m, MachineInputs in = {}, double profile = 0.0) {
  m.begin_tick(in);
  return m.valve_enabled() ? m.next_demand(profile) : 0.0;
}

// Drives a fresh machine to `target` by the ordinary path. `stopping` is
// reached with a moving demand (0.1 m/s) so that the stop takes a while.
void drive_to(RigStateMachine& m, S target) {
  m.begin_tick({});
  if (target == S::kFaulted) return;
  ASSERT_TRUE(m.apply(cmd(K::kReset)).accepted);
  if (target == S::kOff) return;
  ASSERT_TRUE(m.apply(cmd(K::kHydraulicsLow)).accepted);
  if (target == S::kHydraulicsLow) return;
  ASSERT_TRUE(m.apply(cmd(K::kHydraulicsHigh)).accepted);
  if (target == S::kHydraulicsHigh) return;
  ASSERT_TRUE(m.apply(cmd(K::kArm)).accepted);
  if (target == S::kArmed) return;
  ASSERT_TRUE(m.apply(cmd(K::kStart)).accepted);
  for (int k = 0; k < 20; ++k) m.next_demand(0.1 * kT * k), m.begin_tick({});
  if (target == S::kRunning) return;
  if (target == S::kHolding) {
    ASSERT_TRUE(m.apply(cmd(K::kHold)).accepted);
    return;
  }
  ASSERT_TRUE(m.apply(cmd(K::kStop)).accepted);
  ASSERT_EQ(m.state(), S::kStopping);
}

constexpr S kAllStates[] = {S::kOff,     S::kHydraulicsLow, S::kHydraulicsHigh, S::kArmed,
                            S::kRunning, S::kHolding,       S::kStopping,       S::kFaulted};
constexpr K kAllCommands[] = {K::kHydraulicsOff, K::kHydraulicsLow, K::kHydraulicsHigh, K::kArm,   K::kStart,
                              K::kHold,          K::kResume,        K::kStop,           K::kReset, K::kSetpoint,
                              K::kStopAtBlockEnd};

}  // namespace

TEST(RigStateMachine, StartsFaultedWithTheValveSafeAndHydraulicsOff) {
  RigStateMachine m(config());
  EXPECT_EQ(m.state(), S::kFaulted);
  EXPECT_FALSE(m.valve_enabled());
  EXPECT_EQ(m.demand_mode(), DemandMode::kNone);
  EXPECT_EQ(m.hydraulics(), HydraulicsStage::kOff);
}

TEST(RigStateMachine, EveryAllowedTransitionSucceedsWithItsGuardMet) {
  int allowed = 0;
  for (S from : kAllStates) {
    for (K kind : kAllCommands) {
      const TransitionRule& rule = transition_rule(from, kind);
      if (!rule.allowed) continue;
      ++allowed;
      RigStateMachine m(config());
      drive_to(m, from);
      ASSERT_EQ(m.state(), from);
      const auto r = m.apply(cmd(kind, 0.01));
      EXPECT_TRUE(r.accepted) << to_string(from) << " + " << to_string(kind) << ": " << to_string(r.reason);
      EXPECT_EQ(m.state(), rule.to) << to_string(from) << " + " << to_string(kind);
    }
  }
  EXPECT_EQ(allowed, 23);  // the table's size: a changed table changes this test on purpose
}

TEST(RigStateMachine, EveryForbiddenTransitionIsRejectedWithItsReasonAndChangesNothing) {
  int refused = 0;
  for (S from : kAllStates) {
    for (K kind : kAllCommands) {
      const TransitionRule& rule = transition_rule(from, kind);
      if (rule.allowed) continue;
      ++refused;
      RigStateMachine m(config());
      drive_to(m, from);
      const bool valve = m.valve_enabled();
      const auto r = m.apply(cmd(kind, 0.01));
      EXPECT_FALSE(r.accepted) << to_string(from) << " + " << to_string(kind);
      EXPECT_EQ(r.reason, rule.refused);
      EXPECT_NE(r.reason, Rejection::kNone);
      EXPECT_FALSE(to_string(r.reason).empty());
      EXPECT_EQ(m.state(), from);
      EXPECT_EQ(m.valve_enabled(), valve);
    }
  }
  EXPECT_EQ(refused, 88 - 23);
}

TEST(RigStateMachine, RefusalsSayWhatIsMissing) {
  auto reason = [](S from, K kind) {
    RigStateMachine m(config());
    drive_to(m, from);
    return m.apply(cmd(kind)).reason;
  };
  EXPECT_EQ(reason(S::kFaulted, K::kArm), Rejection::kFaulted);
  EXPECT_EQ(reason(S::kOff, K::kHydraulicsHigh), Rejection::kHydraulicsOff);
  EXPECT_EQ(reason(S::kOff, K::kArm), Rejection::kNotHighPressure);
  EXPECT_EQ(reason(S::kHydraulicsHigh, K::kStart), Rejection::kNotArmed);
  EXPECT_EQ(reason(S::kRunning, K::kHydraulicsOff), Rejection::kValveDriven);
  EXPECT_EQ(reason(S::kHolding, K::kStart), Rejection::kUseResume);
  EXPECT_EQ(reason(S::kStopping, K::kArm), Rejection::kStopping);
  EXPECT_EQ(reason(S::kRunning, K::kResume), Rejection::kNotHolding);
}

TEST(RigStateMachine, StagedPressureWaitsForEachStageToSettle) {
  auto c = config();
  c.low_settle_s = 0.1;  // 40 ticks
  c.high_settle_s = 0.05;
  RigStateMachine m(c);
  drive_to(m, S::kOff);
  ASSERT_TRUE(m.apply(cmd(K::kHydraulicsLow)).accepted);
  EXPECT_EQ(m.apply(cmd(K::kHydraulicsHigh)).reason, Rejection::kPressureNotReached);
  for (int k = 0; k < 39; ++k) m.begin_tick({});
  EXPECT_EQ(m.apply(cmd(K::kHydraulicsHigh)).reason, Rejection::kPressureNotReached);
  m.begin_tick({});
  ASSERT_TRUE(m.apply(cmd(K::kHydraulicsHigh)).accepted);
  EXPECT_EQ(m.apply(cmd(K::kArm)).reason, Rejection::kPressureNotReached);
  for (int k = 0; k < 20; ++k) m.begin_tick({});
  EXPECT_TRUE(m.apply(cmd(K::kArm)).accepted);
  EXPECT_TRUE(m.valve_enabled());
}

TEST(RigStateMachine, APressureSwitchOverridesTheSettleTime) {
  auto c = config();
  c.low_settle_s = 100.0;
  RigStateMachine m(c);
  drive_to(m, S::kOff);
  ASSERT_TRUE(m.apply(cmd(K::kHydraulicsLow)).accepted);
  MachineInputs in;
  in.low_pressure_reached = 0;
  m.begin_tick(in);
  EXPECT_EQ(m.apply(cmd(K::kHydraulicsHigh)).reason, Rejection::kPressureNotReached);
  in.low_pressure_reached = 1;
  m.begin_tick(in);
  EXPECT_TRUE(m.apply(cmd(K::kHydraulicsHigh)).accepted);
}

TEST(RigStateMachine, TheValveIsDrivenOnlyOnValidFeedback) {
  RigStateMachine m(config());
  drive_to(m, S::kHydraulicsHigh);
  MachineInputs in;
  in.feedback_valid = false;
  m.begin_tick(in);
  EXPECT_EQ(m.apply(cmd(K::kArm)).reason, Rejection::kFeedbackInvalid);
  EXPECT_FALSE(m.valve_enabled());
  // Feedback lost while driven: faulted on that tick, valve safe.
  m.begin_tick({});
  ASSERT_TRUE(m.apply(cmd(K::kArm)).accepted);
  m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kFaulted);
  EXPECT_FALSE(m.valve_enabled());
}

TEST(RigStateMachine, ResetNeedsEveryFaultGone) {
  RigStateMachine m(config());
  MachineInputs in;
  in.faults_present = true;
  m.begin_tick(in);
  EXPECT_EQ(m.apply(cmd(K::kReset)).reason, Rejection::kFaultsActive);
  EXPECT_EQ(m.state(), S::kFaulted);
  m.begin_tick({});
  const auto r = m.apply(cmd(K::kReset));
  EXPECT_TRUE(r.accepted);
  EXPECT_TRUE(r.reset_latches);
  EXPECT_EQ(m.state(), S::kOff);
}

TEST(RigStateMachine, ResetButtonActsOnARisingEdgeOnly) {
  RigStateMachine m(config());
  MachineInputs in;
  in.reset_input = true;  // held down from power-on: not an edge
  m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kFaulted);
  in.reset_input = false;
  m.begin_tick(in);
  // Pressed while a fault is present: refused...
  in.reset_input = true;
  in.faults_present = true;
  m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kFaulted);
  // ...and still held when the fault clears: no reset behind the operator's back.
  in.faults_present = false;
  for (int k = 0; k < 10; ++k) m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kFaulted);
  // Released and pressed again: reset.
  in.reset_input = false;
  m.begin_tick(in);
  in.reset_input = true;
  m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kOff);
}

TEST(RigStateMachine, InterlockMakesTheValveSafeAtOnceFromAnyState) {
  for (S from : kAllStates) {
    if (from == S::kFaulted) continue;
    RigStateMachine m(config());
    drive_to(m, from);
    MachineInputs in;
    in.limit_action = LimitAction::kInterlock;
    m.begin_tick(in, EventCode::kLimitTripped);
    EXPECT_EQ(m.state(), S::kFaulted) << to_string(from);
    EXPECT_FALSE(m.valve_enabled());
    EXPECT_EQ(m.hydraulics(), HydraulicsStage::kOff);
    ASSERT_GE(m.change_count(), 1u);
    EXPECT_EQ(m.changes()[m.change_count() - 1].cause, EventCode::kLimitTripped);
  }
}

TEST(RigStateMachine, LeavingRunningRampsTheDemandToAHoldWithoutAJump) {
  RigStateMachine m(config());
  drive_to(m, S::kRunning);
  // The demand moves at 0.2 m/s; the hold brings it to rest at 1 m/s^2.
  double profile = 0.0, last = 0.0, last_step = 0.0;
  for (int k = 0; k < 40; ++k) {
    profile += 0.2 * kT;
    m.begin_tick({});
    last_step = m.next_demand(profile) - last;
    last = m.shaper().demand();
  }
  ASSERT_NEAR(last_step, 0.2 * kT, 1e-9);
  ASSERT_TRUE(m.apply(cmd(K::kHold)).accepted);
  EXPECT_EQ(m.state(), S::kHolding);
  int ticks = 0;
  for (; ticks < 1000; ++ticks) {
    m.begin_tick({});
    const double d = m.next_demand(profile + 1.0);  // the profile is ignored while holding
    const double step = d - last;
    EXPECT_GE(step, -1e-12) << "the demand keeps its direction while it slows";
    EXPECT_LE(step, last_step + 1e-12) << "and never speeds up (no jump)";
    last_step = step;
    last = d;
    if (m.shaper().settled()) break;
  }
  // v^2 / (2 a) = 0.02 m of travel, v / a = 0.2 s = 80 ticks.
  EXPECT_NEAR(ticks, 80, 2);
  EXPECT_NEAR(m.shaper().demand() - (profile), 0.02, 0.002);
}

TEST(RigStateMachine, ResumeAndReArmDoNotJump) {
  RigStateMachine m(config());
  drive_to(m, S::kHolding);
  for (int k = 0; k < 200; ++k) tick(m);
  const double held = m.shaper().demand();
  // The profile has moved on while the rig held; resume removes the offset
  // at the setpoint rate instead of jumping to it.
  ASSERT_TRUE(m.apply(cmd(K::kResume)).accepted);
  const double profile = held + 0.01;
  double last = held;
  int k = 0;
  for (; k < 1000; ++k) {
    const double d = tick(m, {}, profile);
    EXPECT_LE(std::abs(d - last), 0.05 * kT + 1e-12);
    last = d;
    if (d == profile) break;
  }
  EXPECT_NEAR(k, 0.01 / (0.05 * kT), 2);  // 80 ticks at 0.05 m/s
  // Stop, then re-arm where the rig now stands: the hold starts at the
  // measured position, and start joins the profile without a step.
  ASSERT_TRUE(m.apply(cmd(K::kStop)).accepted);
  for (int i = 0; i < 400 && m.state() == S::kStopping; ++i) tick(m, {}, profile);
  ASSERT_EQ(m.state(), S::kHydraulicsHigh);
  MachineInputs in;
  in.feedback = profile - 0.003;
  m.begin_tick(in);
  ASSERT_TRUE(m.apply(cmd(K::kArm)).accepted);
  EXPECT_EQ(m.next_demand(0.0), profile - 0.003);
  m.begin_tick(in);
  ASSERT_TRUE(m.apply(cmd(K::kStart)).accepted);
  EXPECT_LE(std::abs(m.next_demand(profile + 0.05) - (profile - 0.003)), 0.05 * kT + 1e-12);
}

TEST(RigStateMachine, SetpointMovesAHeldDemandAtTheSetpointRate) {
  RigStateMachine m(config());
  drive_to(m, S::kArmed);
  EXPECT_EQ(m.apply(cmd(K::kSetpoint, 0.5)).reason, Rejection::kSetpointOutOfRange);
  EXPECT_EQ(m.apply(cmd(K::kSetpoint, std::nan(""))).reason, Rejection::kSetpointOutOfRange);
  ASSERT_TRUE(m.apply(cmd(K::kSetpoint, 0.01)).accepted);
  double last = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double d = tick(m);
    EXPECT_LE(d - last, 0.05 * kT + 1e-12);
    last = d;
  }
  EXPECT_DOUBLE_EQ(last, 0.01);
}

TEST(RigStateMachine, StopActionRampsThenDisarmsAndLatches) {
  RigStateMachine m(config());
  drive_to(m, S::kRunning);
  MachineInputs trip;
  trip.limit_action = LimitAction::kStop;
  m.begin_tick(trip, EventCode::kTrackingError);
  EXPECT_EQ(m.state(), S::kStopping);
  EXPECT_TRUE(m.valve_enabled()) << "a controlled stop keeps the valve under control";
  m.next_demand(0.0);
  for (int k = 0; k < 400 && m.state() == S::kStopping; ++k) tick(m, trip);
  EXPECT_EQ(m.state(), S::kHydraulicsHigh);
  EXPECT_FALSE(m.valve_enabled());
  EXPECT_TRUE(m.stopped_by_trip());
  m.begin_tick(trip);  // still latched
  EXPECT_EQ(m.apply(cmd(K::kArm)).reason, Rejection::kTripLatched);
  m.begin_tick({});  // the loop cleared the latch after a reset
  EXPECT_TRUE(m.apply(cmd(K::kArm)).accepted);
}

TEST(RigStateMachine, HoldActionHoldsAndBlocksResumeWhileLatched) {
  RigStateMachine m(config());
  drive_to(m, S::kRunning);
  MachineInputs trip;
  trip.limit_action = LimitAction::kHold;
  m.begin_tick(trip, EventCode::kTrackingError);
  EXPECT_EQ(m.state(), S::kHolding);
  EXPECT_EQ(m.apply(cmd(K::kResume)).reason, Rejection::kTripLatched);
  m.begin_tick({});
  EXPECT_TRUE(m.apply(cmd(K::kResume)).accepted);
}

TEST(RigStateMachine, IndicateChangesNothing) {
  RigStateMachine m(config());
  drive_to(m, S::kRunning);
  MachineInputs in;
  in.limit_action = LimitAction::kIndicate;
  m.begin_tick(in);
  EXPECT_EQ(m.state(), S::kRunning);
}

TEST(RigStateMachine, AStopThatDoesNotSettleFaults) {
  auto c = config();
  c.hold_deceleration = 1e-3;  // 0.1 m/s takes 100 s to stop
  c.stop_timeout_s = 0.5;
  RigStateMachine m(c);
  drive_to(m, S::kStopping);
  int k = 0;
  for (; k < 1000 && m.state() == S::kStopping; ++k) tick(m);
  EXPECT_EQ(m.state(), S::kFaulted);
  EXPECT_NEAR(k, 200, 2);
  EXPECT_EQ(m.changes()[m.change_count() - 1].cause, EventCode::kStopTimeout);
}

TEST(RigStateMachine, StepAndCommandsDoNotAllocate) {
  RigStateMachine m(config());
  const long before = rigctl::test::allocation_count();
  m.begin_tick({});
  for (K kind : kAllCommands) m.apply(cmd(kind));
  for (int k = 0; k < 100; ++k) tick(m, {}, 0.001 * k);
  EXPECT_EQ(rigctl::test::allocation_count(), before);
}
