// The tick on the real-time path: whole runs, with operator commands,
// limit trips, a hold, a stop ramp and the closing record, make no heap
// allocation; a burst of operator commands is spread over ticks, at most
// OperatorQueueSource::kMaxPerTick per tick.
#include <gtest/gtest.h>

#include <array>
#include <atomic>

#include "allocation_counter.hpp"
#include "rt/control/pi_controller.hpp"
#include "rt/loop/rig_loop.hpp"
#include "rt/procedure/procedure_runner.hpp"

using namespace rigctl;
using K = OperatorCommandKind;

namespace {

constexpr int64_t kPeriod = 2'500'000;
constexpr double kT = 0.0025;

struct ScriptedCommand {
  int64_t tick = -1;
  OperatorCommand command;
};

// A rod that moves at 0.5 x command [m/s]. On the loop thread, before the
// tick reads, it pushes the operator commands scripted for that tick and
// raises the stop request when due, so every run repeats exactly. Nothing
// here allocates once constructed.
class ScriptedRod final : public Driver {
 public:
  ScriptedRod(SpscQueue<OperatorCommand>& queue, std::atomic<bool>& stop) : queue_(queue), stop_(stop) {
    layout_.inputs = {{"x", "m"}};
    layout_.outputs = {{"u", "1"}};
  }
  void at(int64_t tick, K kind, double value = 0.0) {
    script_[count_++] = ScriptedCommand{tick, OperatorCommand{kind, value, static_cast<uint64_t>(count_)}};
  }
  const ChannelLayout& layout() const override { return layout_; }
  void start() override {}
  bool read(Sample& out) override {
    for (std::size_t i = 0; i < count_; ++i) {
      if (script_[i].tick == reads) queue_.try_push(script_[i].command);
    }
    if (reads == stop_at) stop_.store(true);
    x += u * 0.5 * kT;
    out.t_ns = reads * kPeriod;
    out.value[0] = x;
    ++reads;
    return true;
  }
  void write(const Command& c) override { u = c.value[0]; }
  void make_safe() noexcept override { u = 0.0; }
  void stop() override {}

  int64_t stop_at = -1;
  int64_t reads = 0;
  double x = 0.0, u = 0.0;

 private:
  SpscQueue<OperatorCommand>& queue_;
  std::atomic<bool>& stop_;
  std::array<ScriptedCommand, 32> script_{};
  std::size_t count_ = 0;
  ChannelLayout layout_;
};

class CountingSink final : public TelemetrySink {
 public:
  bool push(const TelemetryRecord& r) noexcept override {
    ++records;
    holding_ticks += r.safety_state == SafetyState::kHolding;
    return true;
  }
  int64_t records = 0, holding_ticks = 0;
};

class CountingEvents final : public EventSink {
 public:
  bool push(const EventRecord& e) noexcept override {
    const bool command = e.event.code == EventCode::kCommandAccepted || e.event.code == EventCode::kCommandRejected;
    if (command && e.source == EventSource::kOperator && e.tick < static_cast<int64_t>(commands_at_tick.size())) {
      ++commands_at_tick[static_cast<std::size_t>(e.tick)];
    }
    trips += e.event.action != 0;
    ++events;
    return true;
  }
  std::array<int, 8> commands_at_tick{};
  int trips = 0, events = 0;
};

struct Rig {
  SpscQueue<OperatorCommand> queue{64};
  std::atomic<bool> stop{false};
  ScriptedRod driver{queue, stop};
  PiController pi{[] {
    PiConfig c;
    c.kp = 20.0;
    c.output_limit = 1.0;
    c.period_s = kT;
    return c;
  }()};
  // Ramp from 0 to 0.1 m at 0.02 m/s after 0.1 s, then hold.
  FilteredProfile profile{std::make_unique<RampStepsProfile>(LeadIn{0.0, 0.1, 0.1, 0.02}, std::vector<double>{0.0}, 100.0),
                          0.0, kT};
  CountingSink sink;
  CountingEvents events;

  // The rod's plausibility, a range that only indicates (it trips on the
  // ramp and clears), and a hold past 0.09 m.
  static LimitDetectors detectors() {
    DetectorSpec invalid;
    invalid.kind = DetectorKind::kInvalid;
    invalid.channel = 0;
    DetectorSpec indicate;
    indicate.kind = DetectorKind::kRange;
    indicate.channel = 0;
    indicate.max = 0.005;
    indicate.action = LimitAction::kIndicate;
    indicate.latch = false;
    DetectorSpec hold = indicate;
    hold.max = 0.09;
    hold.action = LimitAction::kHold;
    hold.latch = true;
    return LimitDetectors({invalid, indicate, hold}, 1, 0, kT);
  }

  // Counts the heap allocations of run() alone; with a procedure (and a
  // recovery sink) when given.
  long run_counting_allocations(bool auto_sequence, int64_t max_ticks, LoopResult& result,
                                ProcedureRunner* procedure = nullptr, RecoverySink* recovery = nullptr) {
    LoopOptions o;
    o.period_ns = kPeriod;
    o.max_ticks = max_ticks;
    o.timing_every_ticks = 40;
    SafetyOptions s;
    s.auto_sequence = auto_sequence;
    s.feedback_input = 0;
    s.machine.hold_deceleration = 0.5;
    s.machine.setpoint_rate = 0.02;
    VirtualClock clock;
    RigLoop loop(driver, pi, profile, detectors(), sink, clock, o, s);
    loop.set_event_sink(&events);
    loop.set_operator_commands(&queue);
    if (procedure != nullptr) loop.set_procedure(procedure, recovery, 400);
    const long before = rigctl::test::allocation_count();
    result = loop.run(stop);
    return rigctl::test::allocation_count() - before;
  }
};

}  // namespace

TEST(RigLoopRealtime, AnOperatorRunAllocatesNothing) {
  Rig rig;
  for (K k : {K::kReset, K::kHydraulicsLow, K::kHydraulicsHigh, K::kArm, K::kStart}) rig.driver.at(0, k);
  rig.driver.at(0, K::kResume);  // refused: logged with its reason
  rig.driver.at(600, K::kReset);  // while running: accepted, nothing latched to clear
  rig.driver.at(2000, K::kSetpoint, 0.05);
  rig.driver.at(2600, K::kReset);
  rig.driver.at(2601, K::kResume);
  rig.driver.at(3000, K::kStop);
  rig.driver.at(3400, K::kHydraulicsOff);
  LoopResult result;
  EXPECT_EQ(rig.run_counting_allocations(false, 1'000'000, result), 0);
  EXPECT_GT(rig.sink.holding_ticks, 0) << "the hold trip held the rig";
  EXPECT_GT(rig.events.trips, 1);
  EXPECT_EQ(result.final_safety_state, SafetyState::kOff) << "stop, then hydraulics off, ended the run";
}

TEST(RigLoopRealtime, AnAutomaticRunStoppedByASignalAllocatesNothing) {
  Rig rig;
  rig.driver.at(100, K::kHold);  // an operator queue beside the automatic sequence
  rig.driver.at(200, K::kResume);
  rig.driver.stop_at = 400;  // mid-ramp: the stop ramps the demand to rest
  LoopResult result;
  EXPECT_EQ(rig.run_counting_allocations(true, 100'000, result), 0);
  EXPECT_EQ(result.end_event.code, EventCode::kStopRequested);
  EXPECT_GT(result.ticks, 401) << "the stop ramps over ticks of its own";
}

TEST(RigLoopRealtime, ABurstOfOperatorCommandsIsSpreadOverTicks) {
  Rig rig;
  for (int i = 0; i < 20; ++i) rig.driver.at(0, K::kHold);  // refused (faulted), each logged
  rig.driver.stop_at = 10;
  LoopResult result;
  rig.run_counting_allocations(false, 1'000'000, result);
  constexpr int kMax = OperatorQueueSource::kMaxPerTick;
  EXPECT_EQ(rig.events.commands_at_tick[0], kMax);
  EXPECT_EQ(rig.events.commands_at_tick[1], kMax);
  EXPECT_EQ(rig.events.commands_at_tick[2], 20 - 2 * kMax);
  EXPECT_EQ(rig.events.commands_at_tick[3], 0);
}

// Takes every recovery the loop offers into storage of its own.
class CopyingRecovery final : public RecoverySink {
 public:
  void offer(const ProcedureRecovery& r) noexcept override {
    *last = r;
    ++offers;
  }
  std::unique_ptr<ProcedureRecovery> last = std::make_unique<ProcedureRecovery>();
  int64_t offers = 0;
};

// A procedure on the tick: a ramp, a compensated sine, a peak_valley block
// program with the rainflow count and the peak-valley detector, a repeat
// group and a hold, with recoveries at every cycle: no allocation, and its
// end ends the run.
TEST(RigLoopRealtime, AProcedureRunAllocatesNothing) {
  Rig rig;
  ProcedureSpec spec;
  spec.ramp_rate = 0.02;
  spec.rainflow_channels = {0};
  StepSpec ramp;
  ramp.kind = StepKind::kRamp;
  ramp.level = 0.05;
  ramp.rate = 0.02;
  StepSpec sine;
  sine.kind = StepKind::kSine;
  sine.rows = {{0.05, 0.004, 2.0, 6}};
  sine.compensation.kind = Compensation::kAmplitudePhase;
  sine.peak_valley = PeakValleyDetectorSpec{true, 0, 1, 2, 0.5, 3, LimitAction::kIndicate};
  StepSpec blocks;
  blocks.kind = StepKind::kBlocks;
  blocks.rows = {{0.05, 0.003, 1.0, 3}, {0.052, 0.002, 2.0, 3}};
  blocks.repeats = 2;
  blocks.compensation.kind = Compensation::kPeakValley;
  blocks.has_end_level = true;
  blocks.end_level = 0.04;
  StepSpec begin, end, hold;
  begin.kind = StepKind::kRepeatBegin;
  begin.repeats = 2;
  end.kind = StepKind::kRepeatEnd;
  hold.kind = StepKind::kHold;
  hold.time_s = 0.5;
  spec.steps = {ramp, begin, sine, blocks, end, hold};
  ProcedureRunner procedure(spec, kT, 0);
  CopyingRecovery recovery;
  LoopResult result;
  EXPECT_EQ(rig.run_counting_allocations(true, 1'000'000, result, &procedure, &recovery), 0);
  EXPECT_TRUE(procedure.finished());
  EXPECT_EQ(procedure.status().total_cycles, spec.programmed_cycles());
  EXPECT_EQ(result.end_event.code, EventCode::kProfileFinished);
  EXPECT_GT(recovery.offers, spec.programmed_cycles());
  EXPECT_EQ(recovery.last->status.phase, ProcedurePhase::kDone);
  EXPECT_LT(result.ticks, 1'000'000) << "the procedure's end ended the run";
}
