// Test procedures through the real loop on the simulated quarter car of
// config/quarter_car.yaml: its body-bearing stick/slip friction, plus the
// hidden-effect generator's rod seal friction and worn-seal cross-port
// leakage (tools/hidden_effects/quarter_car.cpp, level 1), neither of which
// the controller or the procedure knows. The wanted sine and the feedback
// are compared here (tests/support/cycle_fit.hpp), not by the runner.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "config/procedure_config.hpp"
#include "config/rig_config.hpp"
#include "cycle_fit.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "rt/loop/rig_loop.hpp"
#include "tools/hidden_effects/rigs.hpp"
#include "tools/run/rig_assembly.hpp"

using namespace rigctl;
using proctest::ProcedureTick;

namespace {

class ProcedureSink final : public TelemetrySink {
 public:
  ProcedureSink(int feedback, int watched) : feedback_(feedback), watched_(watched) { ticks.reserve(200000); }
  bool push(const TelemetryRecord& r) noexcept override {
    if (!r.has_sample || !r.procedure.active) return true;
    ticks.push_back({r.procedure.wanted, r.controller.setpoint, r.sample.value[static_cast<std::size_t>(feedback_)],
                     r.sample.value[static_cast<std::size_t>(watched_)], r.procedure});
    if (r.event.code != EventCode::kNone) events.push_back(r.event);
    return true;
  }
  std::vector<ProcedureTick> ticks;
  std::vector<Event> events;

 private:
  int feedback_, watched_;
};

RigConfig quarter_car_with_hidden_effects() {
  RigConfig c = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
  const RigEffectGenerator& gen = quarter_car_effect_generator();
  gen.apply(c, "actuator_seal_friction", 1.0, 0);
  gen.apply(c, "cross_port_leakage", 1.0, 0);
  EXPECT_TRUE(c.quarter_car.bearing_friction.enabled);
  return c;
}

struct ProcedureResult {
  std::vector<ProcedureTick> ticks;
  std::vector<Event> events;
  LoopResult loop;
  ProcedureStatus status;
};

// Runs `yaml` on the quarter car; `hook(tick, plant)` may change the plant.
template <class Hook>
ProcedureResult run_procedure(const std::string& yaml, double max_s, const std::string& watched, Hook&& hook) {
  RigConfig config = quarter_car_with_hidden_effects();
  AssembledRig rig = assemble_rig(config);
  auto& sim = dynamic_cast<SimDriver&>(*rig.driver);
  auto& plant = dynamic_cast<QuarterCarPlant&>(sim.plant());
  const ChannelLayout& layout = rig.driver->layout();
  const int feedback = layout.input_index(config.controller.feedback);
  ProcedureContext ctx{&layout, feedback, config.loop.period_s};
  const ProcedureSpec spec = procedure_from_string(yaml, "test.yaml", ctx);
  ProcedureRunner runner(spec, config.loop.period_s, feedback);
  ProcedureSink sink(feedback, layout.input_index(watched));
  // The hook runs in the sink's thread of control: before each tick's read.
  struct HookedSink final : TelemetrySink {
    ProcedureSink& inner;
    Hook& hook;
    QuarterCarPlant& plant;
    int64_t n = 0;
    HookedSink(ProcedureSink& i, Hook& h, QuarterCarPlant& p) : inner(i), hook(h), plant(p) {}
    bool push(const TelemetryRecord& r) noexcept override {
      hook(n++, plant);
      return inner.push(r);
    }
  } hooked(sink, hook, plant);
  VirtualClock clock;
  LoopOptions options;
  options.max_ticks = std::llround(max_s / config.loop.period_s);
  rig.driver->start();
  RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, hooked, clock, options, rig.safety);
  loop.set_procedure(&runner, nullptr, 0);
  std::atomic<bool> stop{false};
  ProcedureResult out;
  out.loop = loop.run(stop);
  out.ticks = std::move(sink.ticks);
  out.events = std::move(sink.events);
  out.status = runner.status();
  return out;
}

ProcedureResult run_procedure(const std::string& yaml, double max_s) {
  return run_procedure(yaml, max_s, "x_r", [](int64_t, QuarterCarPlant&) {});
}

std::string sine_procedure(double f, double amplitude, const std::string& compensation) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "ramp_rate: 0.02\n"
                "steps:\n"
                "  - ramp: {level: 0.08, rate: 0.02}\n"
                "  - sine: {mean: 0.08, amplitude: %g, frequency: %g, cycles: 30, compensation: %s,\n"
                "           max_correction: 10}\n",
                amplitude, f, compensation.c_str());
  return buf;
}

}  // namespace

// The demonstration: 2, 5, 10 and 15 Hz at 1 and 2 mm. Compensated,
// cycle 20's fundamental is within 1 % and 2 degrees of the wanted sine;
// uncompensated, the loss is printed and is larger.
TEST(ProcedureQuarterCar, AmplitudePhaseHoldsTheSineByCycle20) {
  for (double amplitude : {0.001, 0.002}) {
    for (double f : {2.0, 5.0, 10.0, 15.0}) {
      const auto on = run_procedure(sine_procedure(f, amplitude, "amplitude_phase"), 60.0);
      const auto off = run_procedure(sine_procedure(f, amplitude, "none"), 60.0);
      ASSERT_EQ(on.status.phase, ProcedurePhase::kDone) << f << " Hz " << amplitude;
      ASSERT_EQ(on.status.total_cycles, 30);
      const auto c = proctest::fit_cycle(on.ticks, 1, 19, 0.08, amplitude);
      const auto u = proctest::fit_cycle(off.ticks, 1, 19, 0.08, amplitude);
      std::printf("   compensated, cycles 6 11 16 20 26 30:");  // the approach, for the record
      for (int k : {5, 10, 15, 19, 25, 29}) {
        const auto ck = proctest::fit_cycle(on.ticks, 1, k, 0.08, amplitude);
        std::printf(" %.4f x %+.2f deg |", ck.amplitude_ratio, ck.phase_deg);
      }
      std::printf("\n");
      std::printf("  %4.1f Hz, %.0f mm: cycle 20 compensated %.4f x, %+.2f deg; without %.4f x, %+.2f deg\n", f,
                  amplitude * 1e3, c.amplitude_ratio, c.phase_deg, u.amplitude_ratio, u.phase_deg);
      EXPECT_NEAR(c.amplitude_ratio, 1.0, 0.01) << f << " Hz " << amplitude;
      EXPECT_NEAR(c.phase_deg, 0.0, 2.0) << f << " Hz " << amplitude;
      EXPECT_GT(std::fabs(u.amplitude_ratio - 1.0) + std::fabs(u.phase_deg) / 100.0,
                std::fabs(c.amplitude_ratio - 1.0) + std::fabs(c.phase_deg) / 100.0);
    }
  }
}

// Five levels under peak_valley: from its 10th cycle every level's feedback
// peak and valley is within 1 % of the level's range.
TEST(ProcedureQuarterCar, PeakValleyBlockProgramReachesEveryLevelByCycle10) {
  const std::string yaml =
      "steps:\n"
      "  - ramp: {level: 0.08, rate: 0.02}\n"
      "  - blocks:\n"
      "      compensation: peak_valley\n"
      "      compensation_gain: 0.6\n"
      "      rows:\n"
      "        - {mean: 0.08, amplitude: 0.004, frequency: 1.0, cycles: 14}\n"
      "        - {mean: 0.09, amplitude: 0.010, frequency: 0.5, cycles: 14}\n"
      "        - {mean: 0.07, amplitude: 0.003, frequency: 2.0, cycles: 14}\n"
      "        - {mean: 0.085, amplitude: 0.006, frequency: 1.0, cycles: 14}\n"
      "        - {mean: 0.075, amplitude: 0.003, frequency: 1.5, cycles: 14}\n";
  // The smallest range is 6 mm: 1 % of it is 3 sd of x_r's 20 um sensor
  // noise; at 4 mm the noisiest sample of a cycle alone crosses the band.
  const double amplitudes[] = {0.004, 0.010, 0.003, 0.006, 0.003};
  const double means[] = {0.08, 0.09, 0.07, 0.085, 0.075};
  const auto r = run_procedure(yaml, 200.0);
  ASSERT_EQ(r.status.phase, ProcedurePhase::kDone);
  ASSERT_EQ(r.status.total_cycles, 70);
  // Each counted cycle's ticks; its peak is the max within it, its valley
  // the min from its middle to the next cycle's middle (the response lags
  // the commanded valley at the cycle's end).
  for (int32_t row = 0; row < 5; ++row) {
    for (int64_t cycle = 9; cycle < 13; ++cycle) {
      std::size_t a = 0, b = 0, next_b = 0;
      bool found = false;
      for (std::size_t i = 0; i < r.ticks.size(); ++i) {
        const auto& s = r.ticks[i].status;
        if (s.step == 1 && s.row == row && s.row_cycles == cycle) {
          if (!found) a = i;
          found = true;
          b = i;
        } else if (found && s.step == 1 && s.row == row && s.row_cycles == cycle + 1) {
          next_b = i;
        }
      }
      ASSERT_TRUE(found);
      double hi = -1e9, lo = 1e9;
      for (std::size_t i = a; i <= b; ++i) hi = std::max(hi, r.ticks[i].y);
      for (std::size_t i = (a + b) / 2; i <= (next_b > b ? (b + 1 + next_b) / 2 : b); ++i) lo = std::min(lo, r.ticks[i].y);
      const double range = 2.0 * amplitudes[row];
      std::printf("  level %d cycle %lld: peak %+.2f %%, valley %+.2f %% of range\n", row + 1,
                  static_cast<long long>(cycle + 1), 100.0 * (hi - (means[row] + amplitudes[row])) / range,
                  100.0 * (lo - (means[row] - amplitudes[row])) / range);
      EXPECT_NEAR(hi, means[row] + amplitudes[row], 0.01 * range) << "level " << row + 1 << " cycle " << cycle + 1;
      EXPECT_NEAR(lo, means[row] - amplitudes[row], 0.01 * range) << "level " << row + 1 << " cycle " << cycle + 1;
    }
  }
}

// The specimen (the suspension spring) softens from 60 s on, to half its
// stiffness over 60 s; the body's peaks and valleys move away from the
// reference and the detector holds the rig, with the reason in the record.
TEST(ProcedureQuarterCar, SofteningSpecimenTripsThePeakValleyDetectorAndHolds) {
  const std::string yaml =
      "steps:\n"
      "  - ramp: {level: 0.08, rate: 0.02}\n"
      "  - sine:\n"
      "      mean: 0.08\n"
      "      amplitude: 0.01\n"
      "      frequency: 1.0\n"
      "      cycles: 400\n"
      "      compensation: amplitude_phase\n"
      "      peak_valley_detector: {channel: x_b, tolerance: 0.05, cycles: 3, action: hold}\n";
  const double ks = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml").quarter_car.spring_stiffness;
  const int64_t soften_from = std::llround(60.0 / 0.0025), soften_ticks = std::llround(60.0 / 0.0025);
  const auto r = run_procedure(yaml, 200.0, "x_b", [&](int64_t tick, QuarterCarPlant& plant) {
    if (tick >= soften_from && tick <= soften_from + soften_ticks) {
      plant.set_spring_stiffness(ks * (1.0 - 0.5 * static_cast<double>(tick - soften_from) / soften_ticks));
    }
  });
  bool tripped = false;
  for (const auto& e : r.events) {
    if (e.code == EventCode::kPeakValleyChange) {
      tripped = true;
      EXPECT_EQ(e.action, static_cast<uint8_t>(LimitAction::kHold));
      std::printf("  peak-valley change %.1f %% of the reference range\n", 100.0 * e.value);
    }
  }
  ASSERT_TRUE(tripped);
  EXPECT_EQ(r.loop.final_state, RigState::kFaulted);  // a hold trip makes the run a faulted one
  EXPECT_EQ(r.loop.end_event.code, EventCode::kPeakValleyChange);
  EXPECT_LT(r.status.total_cycles, 400);  // held: the test did not go on
  EXPECT_GT(r.status.total_cycles, 60);   // not before the softening
}
