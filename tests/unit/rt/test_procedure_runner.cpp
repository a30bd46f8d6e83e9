// The procedure runner (rt/procedure/procedure_runner.hpp) against a plant
// written here: a first-order lag with a gain, stepped once per tick the way
// the loop does (the demand of tick k acts on the sample of tick k+1).
// The quarter car's closed loop is in tests/unit/run/test_procedure_quarter_car.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cycle_fit.hpp"
#include "rt/procedure/procedure_runner.hpp"

using namespace rigctl;

namespace {

constexpr double kTs = 0.0025;

struct LagPlant {
  double gain = 1.0;
  double tau = 0.01;
  double y = 0.0;
  void step(double u) { y += (1.0 - std::exp(-kTs / tau)) * (gain * u - y); }
};

using proctest::ProcedureTick;
using TickLog = ProcedureTick;

StepSpec sine(double mean, double amplitude, double f, int64_t cycles, Compensation c) {
  StepSpec s;
  s.kind = StepKind::kSine;
  s.name = "sine";
  s.rows.push_back({mean, amplitude, f, cycles});
  s.compensation.kind = c;
  return s;
}

// Runs until the procedure ends (or max_ticks); `hook` may change the plant per tick.
template <class Hook>
std::vector<TickLog> play(ProcedureRunner& runner, LagPlant& plant, int64_t max_ticks, Hook&& hook) {
  std::vector<TickLog> log;
  Sample s;
  runner.start(plant.y);
  for (int64_t k = 0; k < max_ticks && !runner.finished(); ++k) {
    hook(k, plant);
    s.value[0] = plant.y;
    const double u = runner.next(s, plant.y);
    log.push_back({runner.status().wanted, u, plant.y, plant.y, runner.status()});
    plant.step(u);
  }
  return log;
}

std::vector<TickLog> play(ProcedureRunner& runner, LagPlant& plant, int64_t max_ticks) {
  return play(runner, plant, max_ticks, [](int64_t, LagPlant&) {});
}

proctest::CycleFit fit_cycle(const std::vector<TickLog>& log, int64_t cycle, double mean, double amplitude) {
  return proctest::fit_cycle(log, 0, cycle, mean, amplitude);
}

}  // namespace

TEST(ProcedureRunner, SineCountsItsCyclesAndTheRampInApart) {
  ProcedureSpec spec;
  spec.steps.push_back(sine(0.0, 0.01, 5.0, 30, Compensation::kNone));
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  const auto log = play(runner, plant, 100000);
  ASSERT_TRUE(runner.finished());
  EXPECT_EQ(runner.status().total_cycles, 30);
  EXPECT_EQ(runner.status().ramp_in_cycles, 1);
  // 31 cycles of 80 ticks (5 Hz at 2.5 ms): the run lasts that long, +-1 tick.
  EXPECT_NEAR(static_cast<double>(log.size()), 31 * 80, 2.0);
  // Never a step in the demand: at most the sine's own slope per tick.
  for (std::size_t i = 1; i < log.size(); ++i) {
    EXPECT_LT(std::fabs(log[i].demand - log[i - 1].demand), 2 * M_PI * 5.0 * 0.01 * kTs * 1.05) << i;
  }
}

// A lag of 10 ms and a gain of 0.8: at 15 Hz the plant answers 0.58 of the
// amplitude 43 degrees late. Compensated, cycle 20 is within 1 % and 2 deg.
TEST(ProcedureRunner, AmplitudePhaseConvergesWithoutOvershoot) {
  for (double f : {2.0, 5.0, 10.0, 15.0}) {
    ProcedureSpec spec;
    spec.steps.push_back(sine(0.05, 0.01, f, 40, Compensation::kAmplitudePhase));
    ProcedureRunner runner(spec, kTs, 0);
    LagPlant plant;
    plant.gain = 0.8;
    plant.y = 0.05 * 0.8;
    const auto log = play(runner, plant, 1000000);
    ASSERT_TRUE(runner.finished()) << f;
    const proctest::CycleFit c20 = fit_cycle(log, 19, 0.05, 0.01);
    EXPECT_NEAR(c20.amplitude_ratio, 1.0, 0.01) << f << " Hz";
    EXPECT_NEAR(c20.phase_deg, 0.0, 2.0) << f << " Hz";
    // The amplitude approaches from below: no cycle overshoots by more than
    // the fit's own scatter.
    for (int64_t k = 1; k < 40; ++k) EXPECT_LT(fit_cycle(log, k, 0.05, 0.01).amplitude_ratio, 1.005) << f << " Hz cycle " << k;
  }
}

TEST(ProcedureRunner, WithoutCompensationTheLossStays) {
  ProcedureSpec spec;
  spec.steps.push_back(sine(0.05, 0.01, 15.0, 30, Compensation::kNone));
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  plant.gain = 0.8;
  const auto log = play(runner, plant, 1000000);
  const proctest::CycleFit c20 = fit_cycle(log, 19, 0.05, 0.01);
  EXPECT_LT(c20.amplitude_ratio, 0.7);
  EXPECT_LT(c20.phase_deg, -30.0);
}

// Five levels, peak_valley: every level's peaks and valleys within 1 % of
// its range by its 10th cycle.
TEST(ProcedureRunner, PeakValleyReachesEveryLevelByCycleTen) {
  ProcedureSpec spec;
  StepSpec b;
  b.kind = StepKind::kBlocks;
  b.name = "blocks";
  b.rows = {{0.05, 0.01, 2.0, 15}, {0.06, 0.02, 1.0, 15}, {0.04, 0.005, 5.0, 15}, {0.05, 0.015, 3.0, 15}, {0.055, 0.008, 4.0, 15}};
  b.repeats = 1;
  b.compensation.kind = Compensation::kPeakValley;
  b.compensation.gain = 0.7;
  spec.steps.push_back(b);
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  plant.gain = 0.85;
  const auto log = play(runner, plant, 1000000);
  ASSERT_TRUE(runner.finished());
  EXPECT_EQ(runner.status().total_cycles, 75);
  // The feedback's extremes over each counted cycle of each row, found here.
  for (int32_t row = 0; row < 5; ++row) {
    const BlockRow& r = b.rows[static_cast<std::size_t>(row)];
    for (int64_t cycle = 9; cycle < 15; ++cycle) {
      double hi = -1e9, lo = 1e9;
      for (const auto& t : log) {
        if (t.status.row == row && t.status.row_cycles == cycle) {
          hi = std::max(hi, t.y);
          lo = std::min(lo, t.y);
        }
      }
      // The response lags: its valley falls just after the window; the
      // window's peak is the cycle's peak, and the next window starts near
      // the valley.
      EXPECT_NEAR(hi, r.mean + r.amplitude, 0.01 * 2 * r.amplitude) << "row " << row << " cycle " << cycle + 1;
    }
  }
}

TEST(ProcedureRunner, RepeatsCountEveryPass) {
  ProcedureSpec spec;
  StepSpec rep;
  rep.kind = StepKind::kRepeatBegin;
  rep.repeats = 3;
  spec.steps.push_back(rep);
  spec.steps.push_back(sine(0.0, 0.01, 10.0, 7, Compensation::kNone));
  StepSpec hold;
  hold.kind = StepKind::kHold;
  hold.time_s = 0.1;
  spec.steps.push_back(hold);
  StepSpec end;
  end.kind = StepKind::kRepeatEnd;
  spec.steps.push_back(end);
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  play(runner, plant, 1000000);
  ASSERT_TRUE(runner.finished());
  EXPECT_EQ(spec.programmed_cycles(), 21);
  EXPECT_EQ(runner.status().total_cycles, 21);
  EXPECT_EQ(runner.status().ramp_in_cycles, 3);
}

// A recovery taken mid-step, restored into a fresh runner, continues at the
// interrupted cycle: the two runs' test cycles add up to the programme.
TEST(ProcedureRunner, RestoredRecoveryContinuesAtTheInterruptedCycle) {
  ProcedureSpec spec;
  spec.steps.push_back(sine(0.05, 0.01, 10.0, 50, Compensation::kAmplitudePhase));
  spec.rainflow_channels = {0};
  ProcedureRunner first(spec, kTs, 0);
  LagPlant plant;
  plant.gain = 0.8;
  auto recovery = std::make_unique<ProcedureRecovery>();
  int64_t at = 0;
  play(first, plant, 1000000, [&](int64_t k, LagPlant&) {
    if (k == 3000) {  // after the 5 s approach and the ramp-in: in cycle ~24
      first.recovery(*recovery);
      at = first.status().total_cycles;
    }
  });
  ASSERT_GT(at, 5);
  ProcedureRunner second(spec, kTs, 0);
  second.restore(*recovery);
  LagPlant moved;
  moved.y = 0.0;  // the actuator stands elsewhere after the crash
  moved.gain = 0.8;
  const auto log = play(second, moved, 1000000);
  ASSERT_TRUE(second.finished());
  EXPECT_EQ(second.status().total_cycles, 50);
  EXPECT_EQ(second.status().ramp_in_cycles, 2);  // the first start's and the resume's
  // The first counted cycle after the resume is the interrupted one.
  for (const auto& t : log) {
    if (t.status.phase == ProcedurePhase::kRun) {
      EXPECT_EQ(t.status.total_cycles, at);
      break;
    }
  }
  // The compensation came back with it: cycle at+1 is already within 1 %.
  EXPECT_NEAR(fit_cycle(log, at + 1, 0.05, 0.01).amplitude_ratio, 1.0, 0.01);
}

TEST(ProcedureRunner, CompensationBeyondItsLimitStopsTheStep) {
  ProcedureSpec spec;
  auto s = sine(0.0, 0.01, 5.0, 100, Compensation::kAmplitudePhase);
  s.compensation.max_factor = 2.0;
  spec.steps.push_back(s);
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  plant.gain = 0.3;  // a broken specimen: the rig cannot reach the amplitude within 2x
  bool tripped = false;
  Event e;
  play(runner, plant, 20000, [&](int64_t, LagPlant&) {
    if (runner.new_trip(e)) tripped = true;
  });
  EXPECT_TRUE(tripped);
  EXPECT_EQ(runner.action(), LimitAction::kStop);
  EXPECT_EQ(e.code, EventCode::kCompensationLimit);
  EXPECT_GT(e.value, 2.0);
}

// The specimen softens: the peak-valley of the watched channel drifts past
// its tolerance for 3 cycles and the detector holds.
TEST(ProcedureRunner, PeakValleyChangeTripsWithItsAction) {
  ProcedureSpec spec;
  auto s = sine(0.0, 0.01, 5.0, 400, Compensation::kNone);
  s.peak_valley.enabled = true;
  s.peak_valley.channel = 0;
  s.peak_valley.tolerance = 0.05;
  s.peak_valley.cycles = 3;
  s.peak_valley.action = LimitAction::kHold;
  spec.steps.push_back(s);
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  Event e;
  int64_t trip_cycle = -1;
  play(runner, plant, 400 * 80, [&](int64_t k, LagPlant& p) {
    if (k > 100 * 80) p.gain = std::max(0.5, 1.0 - (k - 100 * 80) * 2e-5);  // softening from cycle 100 on
    Event now;
    if (trip_cycle < 0 && runner.new_trip(now)) {
      e = now;
      trip_cycle = runner.status().step_cycles;
    }
  });
  ASSERT_GE(trip_cycle, 0);
  EXPECT_EQ(e.code, EventCode::kPeakValleyChange);
  EXPECT_EQ(runner.action(), LimitAction::kHold);
  // A peak (and a valley) moves by 5 % of the range when the amplitude has
  // lost 10 %: 5000 ticks (62 cycles) after cycle 100, then 3 cycles.
  EXPECT_GT(trip_cycle, 155);
  EXPECT_LT(trip_cycle, 172);
}

namespace {

StepSpec blocks(std::vector<BlockRow> rows, int64_t repeats) {
  StepSpec b;
  b.kind = StepKind::kBlocks;
  b.name = "blocks";
  b.rows = std::move(rows);
  b.repeats = repeats;
  return b;
}

}  // namespace

// "Stop at the end of the block" asked mid-pass: the procedure says so on
// the tick its pass ends (never earlier, once), with the request cleared
// (the recovery written there does not stop again) and the counts at a
// whole pass.
TEST(ProcedureRunner, StopAtBlockEndIsDueWhenThePresentPassEnds) {
  ProcedureSpec spec;
  spec.steps.push_back(blocks({{0.0, 0.01, 4.0, 3}, {0.0, 0.02, 2.0, 2}}, 5));
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  Sample s;
  runner.start(plant.y);
  int64_t due_ticks = 0, asked_at_cycles = -1;
  ProcedureStatus at_due;
  for (int64_t k = 0; k < 1000000 && !runner.finished(); ++k) {
    s.value[0] = plant.y;
    const double u = runner.next(s, plant.y);
    plant.step(u);
    // Asked in the second pass's second row.
    if (asked_at_cycles < 0 && runner.status().pass == 1 && runner.status().row == 1) {
      runner.request_stop_at_block_end();
      asked_at_cycles = runner.status().total_cycles;
      EXPECT_TRUE(runner.status().stop_at_block_end);
    }
    if (runner.take_stop_due()) {
      ++due_ticks;
      at_due = runner.status();
    }
  }
  ASSERT_GE(asked_at_cycles, 0);
  EXPECT_EQ(due_ticks, 1);
  EXPECT_EQ(at_due.pass, 2);
  EXPECT_EQ(at_due.row, 0);
  EXPECT_EQ(at_due.row_cycles, 0);
  EXPECT_EQ(at_due.total_cycles, 10);  // two passes of 5 cycles
  EXPECT_FALSE(at_due.stop_at_block_end);
  EXPECT_EQ(runner.status().total_cycles, 25);  // the loop, not the runner, stops the rig
}

// The time left: the programme's nominal length at the start, falling by a
// tick's period each tick of a test cycle, 0 at the end; repeat groups and
// the steps after them counted.
TEST(ProcedureRunner, TimeLeftCountsDownThroughRepeatsAndSteps) {
  ProcedureSpec spec;
  StepSpec rep;
  rep.kind = StepKind::kRepeatBegin;
  rep.repeats = 2;
  spec.steps.push_back(rep);
  spec.steps.push_back(sine(0.0, 0.01, 5.0, 10, Compensation::kNone));  // 2 s
  StepSpec hold;
  hold.kind = StepKind::kHold;
  hold.time_s = 0.5;
  spec.steps.push_back(hold);
  StepSpec end;
  end.kind = StepKind::kRepeatEnd;
  spec.steps.push_back(end);
  spec.steps.push_back(blocks({{0.0, 0.01, 4.0, 4}, {0.0, 0.02, 2.0, 2}}, 3));  // 3 x 2 s
  ProcedureRunner runner(spec, kTs, 0);
  LagPlant plant;
  const auto log = play(runner, plant, 1000000);
  ASSERT_TRUE(runner.finished());
  // The first tick of the first sine's ramp-in: 11 cycles of 0.2 s, the
  // hold, the second pass (11 cycles and the hold), the block program.
  double first_run = -1.0;
  for (const auto& t : log) {
    if (t.status.phase == ProcedurePhase::kRampIn) {
      first_run = t.status.time_left_s;
      break;
    }
  }
  EXPECT_NEAR(first_run, 2.2 + 0.5 + 2.2 + 0.5 + 6.0, 0.01);
  // Within a test cycle it falls by the period per tick.
  for (std::size_t i = 1; i < log.size(); ++i) {
    const auto& a = log[i - 1].status;
    const auto& b = log[i].status;
    if (a.phase == ProcedurePhase::kRun && b.phase == ProcedurePhase::kRun && a.step == b.step &&
        a.total_cycles == b.total_cycles && spec.steps[static_cast<std::size_t>(a.step)].kind != StepKind::kHold) {
      EXPECT_NEAR(a.time_left_s - b.time_left_s, kTs, 1e-9) << i;
    }
  }
  EXPECT_EQ(runner.status().time_left_s, 0.0);
}
