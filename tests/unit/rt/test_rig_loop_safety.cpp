// The loop with the safety core: operator commands from the queue move the
// state machine, refusals and state changes reach the event sink, a stop
// request ramps the demand to a hold before the valve goes safe.
#include <gtest/gtest.h>

#include <functional>
#include <vector>

#include "rt/control/pi_controller.hpp"
#include "rt/loop/rig_loop.hpp"

using namespace rigctl;
using K = OperatorCommandKind;

namespace {

constexpr int64_t kPeriod = 2'500'000;
constexpr double kT = 0.0025;

// A rod that moves at `gain` x command [m/s]; `on_read` lets a test act at a tick.
class RodDriver final : public Driver {
 public:
  RodDriver() {
    layout_.inputs = {{"x", "m"}};
    layout_.outputs = {{"u", "1"}};
  }
  const ChannelLayout& layout() const override { return layout_; }
  void start() override {}
  bool read(Sample& out) override {
    if (on_read) on_read(reads);
    x += u * 0.5 * kT;
    out.t_ns = reads * kPeriod;
    out.value[0] = x;
    ++reads;
    return true;
  }
  void write(const Command& c) override {
    u = c.value[0];
    ++writes;
  }
  void make_safe() noexcept override {
    u = 0.0;
    ++safe_calls;
  }
  void stop() override {}

  std::function<void(int64_t)> on_read;
  double x = 0.0, u = 0.0;
  int64_t reads = 0, writes = 0, safe_calls = 0;

 private:
  ChannelLayout layout_;
};

class NullSink final : public TelemetrySink {
 public:
  bool push(const TelemetryRecord& r) noexcept override {
    records.push_back(r);
    return true;
  }
  std::vector<TelemetryRecord> records;
};

class CollectingEvents final : public EventSink {
 public:
  bool push(const EventRecord& e) noexcept override {
    events.push_back(e);
    return true;
  }
  std::vector<SafetyState> states() const {
    std::vector<SafetyState> out;
    for (const auto& e : events) {
      if (e.event.code == EventCode::kStateChanged) out.push_back(e.state);
    }
    return out;
  }
  std::vector<EventRecord> events;
};

struct Rig {
  RodDriver driver;
  PiController pi{[] {
    PiConfig c;
    c.kp = 20.0;
    c.ki = 0.0;
    c.output_limit = 1.0;
    c.period_s = kT;
    return c;
  }()};
  // Ramp from 0 to 0.1 m at 0.02 m/s after 0.1 s, then hold for long.
  FilteredProfile profile{std::make_unique<RampStepsProfile>(LeadIn{0.0, 0.1, 0.1, 0.02}, std::vector<double>{0.0}, 100.0),
                          0.0, kT};
  NullSink sink;
  CollectingEvents events;
  VirtualClock clock;
  SpscQueue<OperatorCommand> queue{64};
  std::atomic<bool> stop{false};

  LoopResult run(bool auto_sequence, std::vector<DetectorSpec> detectors = {}, int64_t max_ticks = 1'000'000) {
    LoopOptions o;
    o.period_ns = kPeriod;
    o.max_ticks = max_ticks;
    SafetyOptions s;
    s.auto_sequence = auto_sequence;
    s.feedback_input = 0;
    s.machine.hold_deceleration = 0.5;
    s.machine.setpoint_rate = 0.02;
    DetectorSpec invalid;
    invalid.kind = DetectorKind::kInvalid;
    invalid.channel = 0;
    detectors.insert(detectors.begin(), invalid);
    RigLoop loop(driver, pi, profile, LimitDetectors(std::move(detectors), 1, 0, kT), sink, clock, o, s);
    loop.set_event_sink(&events);
    loop.set_operator_commands(&queue);
    return loop.run(stop);
  }
  void send(K kind, uint64_t seq, double value = 0.0) { ASSERT_TRUE(queue.try_push(OperatorCommand{kind, value, seq})); }
  // Largest tick-to-tick change of the demand over the ticks the valve was driven.
  double max_demand_step() const {
    double worst = 0.0;
    for (std::size_t k = 1; k < sink.records.size(); ++k) {
      const auto& a = sink.records[k - 1];
      const auto& b = sink.records[k];
      if (a.valve_enabled && b.valve_enabled && b.has_sample) {
        worst = std::max(worst, std::abs(b.controller.setpoint - a.controller.setpoint));
      }
    }
    return worst;
  }
};

}  // namespace

TEST(RigLoopSafety, OperatorCommandsWalkTheRigThroughItsStates) {
  Rig rig;
  rig.driver.on_read = [&](int64_t tick) {
    if (tick == 0) {
      uint64_t seq = 1;
      for (K k : {K::kReset, K::kHydraulicsLow, K::kHydraulicsHigh, K::kArm, K::kStart}) rig.send(k, seq++);
    }
    if (tick == 400) rig.send(K::kHold, 10);
    if (tick == 600) rig.send(K::kResume, 11);
    if (tick == 800) rig.stop = true;
  };
  const auto result = rig.run(false);
  using S = SafetyState;
  const std::vector<S> expected{S::kOff,     S::kHydraulicsLow, S::kHydraulicsHigh, S::kArmed, S::kRunning,
                                S::kHolding, S::kRunning,       S::kStopping,       S::kHydraulicsHigh};
  EXPECT_EQ(rig.events.states(), expected);
  EXPECT_EQ(result.final_state, RigState::kStopped);
  EXPECT_EQ(result.end_event.code, EventCode::kStopRequested);
  EXPECT_GT(result.ticks, 800) << "the stop ramps over ticks of its own";
  EXPECT_LE(rig.max_demand_step(), 0.02 * kT + 1e-12) << "no demand jump at hold, resume or stop";
  int accepted = 0;
  for (const auto& e : rig.events.events) accepted += e.event.code == EventCode::kCommandAccepted;
  EXPECT_EQ(accepted, 8);  // 7 commands and the stop request
  EXPECT_EQ(rig.events.events.back().event.code, EventCode::kStopRequested);
}

TEST(RigLoopSafety, ARefusedCommandIsLoggedWithItsReasonAndSequenceAndChangesNothing) {
  Rig rig;
  rig.driver.on_read = [&](int64_t tick) {
    if (tick == 0) rig.send(K::kArm, 41);  // faulted at power-on: reset first
    if (tick == 5) rig.stop = true;
  };
  rig.run(false);
  const EventRecord* refused = nullptr;
  for (const auto& e : rig.events.events) {
    if (e.event.code == EventCode::kCommandRejected) refused = &e;
  }
  ASSERT_NE(refused, nullptr);
  EXPECT_EQ(refused->sequence, 41u);
  EXPECT_EQ(refused->source, EventSource::kOperator);
  EXPECT_EQ(refused->event.detail, static_cast<uint8_t>(Rejection::kFaulted));
  EXPECT_EQ(refused->state, SafetyState::kFaulted);
  EXPECT_EQ(rig.driver.writes, 0) << "the valve was never driven";
}

TEST(RigLoopSafety, AutomaticSequenceStopsWithARampWhenTheRunEndsMidMotion) {
  Rig rig;
  // 2 s: in the middle of the ramp (0.02 m/s).
  const auto result = rig.run(true, {}, 800);
  EXPECT_EQ(result.final_state, RigState::kStopped);
  EXPECT_EQ(result.final_safety_state, SafetyState::kOff);
  EXPECT_EQ(result.end_event.code, EventCode::kProfileFinished);
  // 0.02 m/s at 0.5 m/s^2: 0.04 s = 16 ticks of stopping.
  EXPECT_NEAR(static_cast<double>(result.ticks - 800), 16.0, 2.0);
  EXPECT_LE(rig.max_demand_step(), 0.02 * kT + 1e-12);
  EXPECT_EQ(rig.sink.records.back().state, RigState::kStopped);
}

TEST(RigLoopSafety, AHoldTripHoldsTheRigAndTheRunEndsFaulted) {
  Rig rig;
  DetectorSpec range;
  range.kind = DetectorKind::kRange;
  range.channel = 0;
  range.max = 0.01;  // reached on the ramp at ~0.6 s
  range.action = LimitAction::kHold;
  const auto result = rig.run(true, {range}, 800);
  bool held = false;
  for (const auto& r : rig.sink.records) held = held || r.safety_state == SafetyState::kHolding;
  EXPECT_TRUE(held);
  EXPECT_EQ(result.final_state, RigState::kFaulted) << "a limit tripped";
  EXPECT_EQ(result.end_event.code, EventCode::kLimitTripped);
  EXPECT_LE(rig.max_demand_step(), 0.02 * kT + 1e-12);
}

TEST(RigLoopSafety, AnInterlockMakesTheValveSafeOnTheTickItTrips) {
  Rig rig;
  DetectorSpec range;
  range.kind = DetectorKind::kRange;
  range.channel = 0;
  range.max = 0.01;
  range.action = LimitAction::kInterlock;
  const auto result = rig.run(true, {range}, 800);
  EXPECT_EQ(result.final_state, RigState::kFaulted);
  EXPECT_EQ(result.end_event.code, EventCode::kLimitTripped);
  EXPECT_GT(result.end_event.value, 0.01);
  EXPECT_EQ(rig.driver.reads, result.ticks + 1) << "the run ended on the tick that read the trip";
  EXPECT_EQ(rig.driver.writes, result.ticks) << "nothing written on that tick";
  EXPECT_EQ(rig.driver.u, 0.0) << "the valve is at its safe command";
  EXPECT_GE(rig.driver.safe_calls, 1);
}

// "Stop at the end of the block" asks a test procedure; a run without one
// refuses it with that reason, even while running, and keeps running.
TEST(RigLoopSafety, StopAtBlockEndWithoutAProcedureIsRefusedAndChangesNothing) {
  Rig rig;
  rig.driver.on_read = [&](int64_t tick) {
    if (tick == 0) {
      uint64_t seq = 1;
      for (K k : {K::kReset, K::kHydraulicsLow, K::kHydraulicsHigh, K::kArm, K::kStart}) rig.send(k, seq++);
    }
    if (tick == 200) rig.send(K::kStopAtBlockEnd, 20);
    if (tick == 400) rig.stop = true;
  };
  rig.run(false);
  const EventRecord* refused = nullptr;
  for (const auto& e : rig.events.events) {
    if (e.event.code == EventCode::kCommandRejected) refused = &e;
  }
  ASSERT_NE(refused, nullptr);
  EXPECT_EQ(refused->sequence, 20u);
  EXPECT_EQ(refused->event.detail, static_cast<uint8_t>(Rejection::kNoProcedure));
  EXPECT_EQ(refused->state, SafetyState::kRunning);
  using S = SafetyState;
  const std::vector<S> expected{S::kOff,     S::kHydraulicsLow, S::kHydraulicsHigh, S::kArmed,
                                S::kRunning, S::kStopping,      S::kHydraulicsHigh};
  EXPECT_EQ(rig.events.states(), expected);
}
