// Several control channels in one tick (issue 31 item 1), in simulated time:
// every channel's controller runs each period on its own feedback, demand
// and output; the records carry every channel in order; a limit trip on one
// channel's input makes every output safe; a run with 8 channels allocates
// nothing on the tick.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <memory>
#include <vector>

#include "allocation_counter.hpp"
#include "rt/control/pi_controller.hpp"
#include "rt/loop/rig_loop.hpp"

using namespace rigctl;

namespace {

constexpr int64_t kPeriod = 2'500'000;
constexpr double kT = 0.0025;

// N rods, rod i moving at 0.5 x its command [m/s]; every write and every
// make_safe is counted, so a test sees what reached the valves.
class Rods final : public Driver {
 public:
  explicit Rods(std::size_t n) : n_(n) {
    for (std::size_t i = 0; i < n; ++i) {
      layout_.inputs.push_back({"x_" + std::to_string(i + 1), "m"});
      layout_.outputs.push_back({"u_" + std::to_string(i + 1), "1"});
    }
  }
  const ChannelLayout& layout() const override { return layout_; }
  void start() override {}
  bool read(Sample& out) override {
    for (std::size_t i = 0; i < n_; ++i) {
      x[i] += u[i] * 0.5 * kT;
      out.value[i] = x[i];
    }
    out.t_ns = reads * kPeriod;
    ++reads;
    return true;
  }
  void write(const Command& c) override {
    for (std::size_t i = 0; i < n_; ++i) u[i] = c.value[i];
    ++writes;
  }
  void make_safe() noexcept override {
    u.fill(0.0);
    ++safe_calls;
  }
  void stop() override {}

  std::array<double, kMaxOutputs> x{}, u{};
  int64_t reads = 0, writes = 0, safe_calls = 0;

 private:
  std::size_t n_;
  ChannelLayout layout_;
};

// Keeps every record in storage reserved before the run.
class KeepingSink final : public TelemetrySink {
 public:
  explicit KeepingSink(std::size_t capacity) { records.reserve(capacity); }
  bool push(const TelemetryRecord& r) noexcept override {
    if (records.size() < records.capacity()) records.push_back(r);
    return true;
  }
  std::vector<TelemetryRecord> records;
};

PiConfig pi_for(int channel) {
  PiConfig c;
  c.kp = 20.0;
  c.ki = 0.0;
  c.output_limit = 1.0;
  c.period_s = kT;
  c.feedback_input = channel;
  c.output_index = channel;
  return c;
}

// Channel i ramps from 0 to its own target, 0.01 (i + 1) m, at 0.02 m/s after 0.1 s.
double target_of(std::size_t channel) { return 0.01 * static_cast<double>(channel + 1); }

struct MultiRig {
  explicit MultiRig(std::size_t n, LimitDetectors limits = LimitDetectors({}, 0, 0, kT))
      : n(n), driver(n), sink(20000), detectors(std::move(limits)) {
    for (std::size_t i = 0; i < n; ++i) {
      pis.push_back(std::make_unique<PiController>(pi_for(static_cast<int>(i))));
      profiles.push_back(std::make_unique<FilteredProfile>(
          std::make_unique<RampStepsProfile>(LeadIn{0.0, target_of(i), 0.1, 0.02}, std::vector<double>{0.0}, 100.0),
          0.0, kT));
    }
    for (std::size_t i = 1; i < n; ++i) more.push_back({pis[i].get(), profiles[i].get(), static_cast<int>(i)});
  }

  LoopResult run(int64_t ticks, long* allocations = nullptr) {
    LoopOptions o;
    o.period_ns = kPeriod;
    o.max_ticks = ticks;
    o.timing_every_ticks = 40;
    SafetyOptions s;
    s.auto_sequence = true;
    s.feedback_input = 0;
    s.machine.hold_deceleration = 0.5;
    s.machine.setpoint_rate = 0.02;
    VirtualClock clock;
    RigLoop loop(driver, *pis[0], *profiles[0], detectors, sink, clock, o, s);
    loop.set_more_channels(more);
    const std::atomic<bool> never{false};
    const long before = rigctl::test::allocation_count();
    LoopResult r = loop.run(never);
    if (allocations != nullptr) *allocations = rigctl::test::allocation_count() - before;
    return r;
  }

  std::size_t n;
  Rods driver;
  KeepingSink sink;
  LimitDetectors detectors;
  std::vector<std::unique_ptr<PiController>> pis;
  std::vector<std::unique_ptr<FilteredProfile>> profiles;
  std::vector<ControlChannel> more;
};

}  // namespace

TEST(RigLoopChannels, EveryChannelFollowsItsOwnDemandWithItsOwnValve) {
  MultiRig rig(2);
  const LoopResult r = rig.run(1200);  // 3 s: both ramps end by 2.1 s
  EXPECT_EQ(r.final_state, RigState::kStopped);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(rig.driver.x[i], target_of(i), 1e-3) << "rod " << i + 1 << " stands at its own target";
  }
  // The records carry both channels, in order, each its own demand, feedback and output.
  const TelemetryRecord& mid = rig.sink.records[600];  // 1.5 s: both ramping
  ASSERT_EQ(mid.channel_count, 2);
  EXPECT_NEAR(mid.controller.setpoint, std::min(target_of(0), 0.02 * (1.5 - 0.1)), 1e-3);
  EXPECT_NEAR(mid.more_channels[0].setpoint, std::min(target_of(1), 0.02 * (1.5 - 0.1)), 1e-3);
  EXPECT_DOUBLE_EQ(mid.controller.measurement, mid.sample.value[0]);
  EXPECT_DOUBLE_EQ(mid.more_channels[0].measurement, mid.sample.value[1]);
  EXPECT_DOUBLE_EQ(mid.more_channels[0].output, mid.command.value[1]);
  EXPECT_DOUBLE_EQ(mid.controller.output, mid.command.value[0]);
  // Late in the run rod 1 holds 10 mm while rod 2 still ramps: their commands differ.
  const TelemetryRecord& late = rig.sink.records[900];
  EXPECT_NEAR(late.controller.setpoint, target_of(0), 1e-9);
  EXPECT_GT(late.more_channels[0].setpoint, target_of(0) + 0.005);
  EXPECT_NE(late.command.value[0], late.command.value[1]);
}

TEST(RigLoopChannels, ALimitTripOnTheSecondChannelNullsEveryValve) {
  // Interlock when rod 2 passes 15 mm (its target is 20 mm; rod 1 stops at 10 mm).
  DetectorSpec limit;
  limit.name = "limits.x_2";
  limit.kind = DetectorKind::kRange;
  limit.channel = 1;
  limit.min = -1.0;
  limit.max = 0.015;
  limit.action = LimitAction::kInterlock;
  MultiRig rig(2, LimitDetectors({limit}, 2, 0, kT));
  const LoopResult r = rig.run(2000);
  EXPECT_EQ(r.final_state, RigState::kFaulted);
  EXPECT_EQ(r.end_event.code, EventCode::kLimitTripped);
  EXPECT_EQ(r.end_event.channel, 1) << "the trip names the second channel's input";
  EXPECT_GE(rig.driver.safe_calls, 1);
  EXPECT_EQ(rig.driver.u[0], 0.0) << "the first post's valve is at null too";
  EXPECT_EQ(rig.driver.u[1], 0.0);
  // Before the trip rod 1 was being driven (a non-zero command): the interlock stopped a live valve.
  bool first_valve_driven = false;
  for (const auto& rec : rig.sink.records) first_valve_driven = first_valve_driven || rec.command.value[0] != 0.0;
  EXPECT_TRUE(first_valve_driven);
  EXPECT_GT(rig.driver.x[1], 0.015);
  EXPECT_LT(rig.driver.x[1], 0.016) << "the run ended on the tick the limit was crossed";
}

TEST(RigLoopChannels, EightChannelsRunWithoutAllocatingAndStopTogether) {
  MultiRig rig(8);
  long allocations = -1;
  const LoopResult r = rig.run(2400, &allocations);  // 6 s: the 80 mm ramp ends at 4.1 s
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(r.final_state, RigState::kStopped);
  for (std::size_t i = 0; i < 8; ++i) EXPECT_NEAR(rig.driver.x[i], target_of(i), 2e-3) << "rod " << i + 1;
  EXPECT_EQ(rig.sink.records[100].channel_count, 8);
}

TEST(RigLoopChannels, MoreChannelsThanTheLoopHoldsAreRefused) {
  MultiRig rig(2);
  std::vector<ControlChannel> too_many(kMaxChannels, rig.more[0]);
  LoopOptions o;
  SafetyOptions s;
  VirtualClock clock;
  RigLoop loop(rig.driver, *rig.pis[0], *rig.profiles[0], rig.detectors, rig.sink, clock, o, s);
  EXPECT_THROW(loop.set_more_channels(too_many), std::invalid_argument);
}
