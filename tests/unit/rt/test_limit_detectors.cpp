// Each limit detector trips on its condition (and only then), reports its
// action, latches until a reset after the condition cleared, and never
// allocates on the loop.
#include <gtest/gtest.h>

#include <cmath>

#include "allocation_counter.hpp"
#include "rt/safety/limit_detectors.hpp"

using namespace rigctl;

namespace {

constexpr double kT = 0.0025;

DetectorSpec spec(DetectorKind kind, int channel, LimitAction action = LimitAction::kInterlock) {
  DetectorSpec s;
  s.name = std::string(to_string(kind));
  s.kind = kind;
  s.channel = channel;
  s.action = action;
  return s;
}

struct Bench {
  explicit Bench(std::vector<DetectorSpec> specs, int feedback = 0) : d(std::move(specs), 2, feedback, kT) {}
  const DetectorResult& step(double x, double u = 0.0, bool driven = true) {
    sample.value[0] = x;
    sample.t_ns += 2'500'000;
    command.value[0] = u;
    now_ns += 2'500'000;
    DetectorInputs in;
    in.sample = &sample;
    in.now_ns = now_ns;
    in.demand = demand;
    in.command = &command;
    in.valve_driven = driven;
    in.overruns = overruns;
    return d.check(in);
  }
  LimitDetectors d;
  Sample sample;
  Command command;
  int64_t now_ns = 0;
  double demand = 0.0;
  int64_t overruns = 0;
};

}  // namespace

TEST(LimitDetectors, RangeTripsWithItsActionAndLatchesUntilAResetAfterItCleared) {
  auto s = spec(DetectorKind::kRange, 0, LimitAction::kStop);
  s.min = -0.01;
  s.max = 0.1;
  Bench b({s});
  EXPECT_EQ(b.step(0.05).action, LimitAction::kNone);
  const auto& r = b.step(0.12);
  EXPECT_EQ(r.action, LimitAction::kStop);
  EXPECT_TRUE(r.faults_present);
  ASSERT_EQ(r.new_count, 1u);
  EXPECT_EQ(r.worst_new.code, EventCode::kLimitTripped);
  EXPECT_DOUBLE_EQ(r.worst_new.value, 0.12);
  EXPECT_EQ(b.step(0.13).new_count, 0u) << "a trip is reported once, on its rising edge";
  EXPECT_EQ(b.d.clear_latches(), 0) << "no reset while the condition is present";
  EXPECT_EQ(b.step(0.05).action, LimitAction::kStop) << "latched";
  EXPECT_FALSE(b.d.last().faults_present);
  EXPECT_EQ(b.d.clear_latches(), 1);
  EXPECT_EQ(b.step(0.05).action, LimitAction::kNone);
}

TEST(LimitDetectors, AnUnlatchedDetectorClearsByItself) {
  auto s = spec(DetectorKind::kRange, 0, LimitAction::kIndicate);
  s.max = 0.1;
  s.latch = false;
  Bench b({s});
  EXPECT_EQ(b.step(0.2).action, LimitAction::kIndicate);
  EXPECT_FALSE(b.d.last().faults_present) << "an indication is not a fault";
  EXPECT_EQ(b.step(0.0).action, LimitAction::kNone);
}

TEST(LimitDetectors, NotANumberAndDriverFlagsAreInvalidFeedback) {
  Bench b({spec(DetectorKind::kInvalid, 0)});
  EXPECT_FALSE(b.step(0.0).feedback_invalid);
  const auto& r = b.step(std::nan(""));
  EXPECT_EQ(r.worst_new.code, EventCode::kInputInvalid);
  EXPECT_TRUE(r.feedback_invalid);
  Bench flagged({spec(DetectorKind::kInvalid, 0)});
  flagged.sample.status = 1u;
  EXPECT_EQ(flagged.step(0.0).action, LimitAction::kInterlock);
}

TEST(LimitDetectors, RateOfChange) {
  auto s = spec(DetectorKind::kRate, 0, LimitAction::kStop);
  s.max = 0.5;  // [m/s]
  Bench b({s});
  double x = 0.0;
  for (int k = 0; k < 10; ++k) EXPECT_EQ(b.step(x += 0.4 * kT).action, LimitAction::kNone);
  const auto& r = b.step(x += 0.6 * kT);
  EXPECT_EQ(r.worst_new.code, EventCode::kRateLimit);
  EXPECT_NEAR(r.worst_new.value, 0.6, 1e-9);
}

TEST(LimitDetectors, TrackingErrorOnlyWhileTheValveIsDrivenAndAfterItsPersistence) {
  auto s = spec(DetectorKind::kTrackingError, 0, LimitAction::kHold);
  s.max = 0.005;
  s.duration_s = 4 * kT;
  Bench b({s});
  b.demand = 0.02;
  EXPECT_EQ(b.step(0.0, 0.0, false).action, LimitAction::kNone) << "valve not driven";
  for (int k = 0; k < 3; ++k) EXPECT_EQ(b.step(0.0).action, LimitAction::kNone) << k;
  const auto& r = b.step(0.0);
  EXPECT_EQ(r.action, LimitAction::kHold);
  EXPECT_EQ(r.worst_new.code, EventCode::kTrackingError);
  EXPECT_DOUBLE_EQ(r.worst_new.value, 0.02);
}

TEST(LimitDetectors, ValveSaturationForItsDuration) {
  auto s = spec(DetectorKind::kValveSaturation, 0, LimitAction::kStop);
  s.max = 0.98;
  s.duration_s = 0.1;  // 40 ticks
  Bench b({s});
  for (int k = 0; k < 39; ++k) ASSERT_EQ(b.step(0.0, -1.0).action, LimitAction::kNone) << k;
  EXPECT_EQ(b.step(0.0, -1.0).worst_new.code, EventCode::kValveSaturated);
  Bench brief({s});
  for (int k = 0; k < 100; ++k) ASSERT_EQ(brief.step(0.0, k % 30 == 0 ? 0.0 : 1.0).action, LimitAction::kNone);
}

TEST(LimitDetectors, SampleAgeWhenTheTimeStampStopsAdvancing) {
  auto s = spec(DetectorKind::kSampleAge, -1);
  s.max = 0.0135;  // a little over five periods
  Bench b({s});
  b.step(0.0);
  const int64_t frozen = b.sample.t_ns;
  int k = 0;
  for (; k < 20; ++k) {
    b.sample.t_ns = frozen - 2'500'000;  // step() adds one period: the stamp stays
    if (b.step(0.0).action != LimitAction::kNone) break;
  }
  EXPECT_EQ(k, 5) << "tripped after the sixth stale tick (age 15 ms > 12.5 ms)";
  EXPECT_EQ(b.d.last().worst_new.code, EventCode::kSampleStale);
}

TEST(LimitDetectors, OverrunsCountedOverASlidingWindow) {
  auto s = spec(DetectorKind::kOverruns, -1, LimitAction::kIndicate);
  s.max_count = 3;
  s.window_s = 0.1;  // 40 ticks
  Bench b({s});
  // One overrun every 20 ticks: never more than 2 in a window.
  for (int k = 0; k < 200; ++k) {
    if (k % 20 == 0) ++b.overruns;
    ASSERT_EQ(b.step(0.0).action, LimitAction::kNone) << k;
  }
  // A burst of four within the window trips it.
  EventCode tripped = EventCode::kNone;
  for (int k = 0; k < 4; ++k) {
    ++b.overruns;
    if (b.step(0.0).new_count > 0) tripped = b.d.last().worst_new.code;
  }
  EXPECT_EQ(b.d.last().action, LimitAction::kIndicate);
  EXPECT_EQ(tripped, EventCode::kOverruns);
}

TEST(LimitDetectors, OpenCircuitTransducerAtItsRail) {
  auto s = spec(DetectorKind::kOpenCircuit, 0);
  s.min = -0.1999;
  s.max = 0.1999;
  Bench b({s});
  EXPECT_EQ(b.step(0.1998).action, LimitAction::kNone);
  const auto& r = b.step(0.19999);
  EXPECT_EQ(r.worst_new.code, EventCode::kOpenCircuit);
  EXPECT_TRUE(r.feedback_invalid);
}

TEST(LimitDetectors, StuckSensorOnlyWhileCommanded) {
  auto s = spec(DetectorKind::kStuck, 0);
  s.tolerance = 1e-6;
  s.command_min = 0.2;
  s.duration_s = 0.05;  // 20 ticks
  Bench b({s});
  // Not commanded: a still sensor is fine.
  for (int k = 0; k < 100; ++k) ASSERT_EQ(b.step(0.01, 0.1).action, LimitAction::kNone);
  // Commanded and moving: fine.
  double x = 0.01;
  for (int k = 0; k < 100; ++k) ASSERT_EQ(b.step(x += 1e-4, 0.5).action, LimitAction::kNone);
  // Commanded and still: stuck after its duration.
  int k = 0;
  for (; k < 100 && b.step(x, 0.5).action == LimitAction::kNone; ++k) {
  }
  EXPECT_EQ(k, 19) << "the 20th still tick trips";
  EXPECT_EQ(b.d.last().worst_new.code, EventCode::kSensorStuck);
}

TEST(LimitDetectors, TheMostSevereNewTripIsReportedAndEveryTripIsListed) {
  auto indicate = spec(DetectorKind::kRange, 0, LimitAction::kIndicate);
  indicate.max = 0.05;
  auto interlock = spec(DetectorKind::kRange, 0, LimitAction::kInterlock);
  interlock.max = 0.1;
  auto hold = spec(DetectorKind::kRange, 0, LimitAction::kHold);
  hold.max = 0.08;
  Bench b({indicate, interlock, hold});
  const auto& r = b.step(0.2);
  EXPECT_EQ(r.action, LimitAction::kInterlock);
  EXPECT_EQ(r.new_count, 3u);
  EXPECT_EQ(r.worst_new.detector, 1);
  EXPECT_EQ(r.new_trips[0].action, LimitAction::kIndicate);
  EXPECT_EQ(r.new_trips[2].action, LimitAction::kHold);
}

TEST(LimitDetectors, CheckDoesNotAllocate) {
  auto over = spec(DetectorKind::kOverruns, -1);
  over.max_count = 1;
  auto rate = spec(DetectorKind::kRate, 0);
  rate.max = 1.0;
  Bench b({over, rate, spec(DetectorKind::kStuck, 0), spec(DetectorKind::kInvalid, 1)});
  const long before = rigctl::test::allocation_count();
  for (int k = 0; k < 1000; ++k) b.step(std::sin(k * 0.1), 0.5);
  b.d.clear_latches();
  EXPECT_EQ(rigctl::test::allocation_count(), before);
}
