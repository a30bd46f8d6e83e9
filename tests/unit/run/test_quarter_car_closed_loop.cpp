// The quarter-car step test of seed 000, closed loop through the real loop,
// PI controller, simulated driver and sensor models of the shipped config.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <vector>

#include "config/rig_config.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "rt/loop/rig_loop.hpp"
#include "tools/run/rig_assembly.hpp"

using namespace rigctl;

namespace {

struct Tick {
  double t, x_ref, u, x_r, x_w, x_b, p1, p2;  // as measured by the loop
  QuarterCarState truth;
  double f_bearing;
  bool stuck;
};

// Records what the loop publishes plus the plant's true state on each tick.
class RecordingSink final : public TelemetrySink {
 public:
  RecordingSink(const QuarterCarPlant& plant, const ChannelLayout& layout) : plant_(plant) {
    for (const char* name : {"x_r", "x_w", "x_b", "p1", "p2", "sim_f_bearing", "sim_bearing_stuck"}) {
      index_.push_back(static_cast<std::size_t>(layout.input_index(name)));
    }
    ticks.reserve(9000);
  }
  bool push(const TelemetryRecord& r) noexcept override {
    if (!r.has_sample) return true;
    const auto& v = r.sample.value;
    ticks.push_back({r.sample.t_ns * 1e-9, r.controller.setpoint, r.command.value[0], v[index_[0]], v[index_[1]],
                     v[index_[2]], v[index_[3]], v[index_[4]], plant_.state(), v[index_[5]], v[index_[6]] > 0.5});
    return true;
  }
  std::vector<Tick> ticks;

 private:
  const QuarterCarPlant& plant_;
  std::vector<std::size_t> index_;
};

struct StepRun {
  std::vector<Tick> ticks;
  RigConfig config;
  LoopResult result;
  const Tick& at(double t) const { return ticks.at(static_cast<std::size_t>(std::lround(t / 0.0025))); }
};

StepRun run_step_test(bool friction) {
  StepRun run;
  run.config = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
  run.config.quarter_car.bearing_friction.enabled = friction;
  AssembledRig rig = assemble_rig(run.config);
  auto& plant = dynamic_cast<QuarterCarPlant&>(dynamic_cast<SimDriver&>(*rig.driver).plant());
  RecordingSink sink(plant, rig.driver->layout());
  VirtualClock clock;
  LoopOptions options;
  options.max_ticks = std::lround(rig.profile_duration_s / run.config.loop.period_s);
  options.start_from_input = rig.profile_start_input;
  rig.driver->start();
  // As `rigctl run` runs it: the configured detectors and state machine.
  RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, sink, clock, options, rig.safety);
  std::atomic<bool> stop{false};
  run.result = loop.run(stop);
  run.ticks = std::move(sink.ticks);
  return run;
}

const StepRun& with_friction() {
  static const StepRun run = run_step_test(true);
  return run;
}
const StepRun& without_friction() {
  static const StepRun run = run_step_test(false);
  return run;
}

// Steps of the shipped profile: 1 s hold + 80 mm at 20 mm/s, then 4 s each.
constexpr double kFirstStep = 5.0, kStepHold = 4.0;
constexpr int kSteps = 4;

// First time after t0 when |signal - signal(t0)| exceeds threshold.
template <typename Get>
double departure_time(const StepRun& run, double t0, double threshold, Get get) {
  const double ref = get(run.at(t0));
  for (std::size_t i = static_cast<std::size_t>(std::lround(t0 / 0.0025)); i < run.ticks.size(); ++i) {
    if (std::abs(get(run.ticks[i]) - ref) > threshold) return run.ticks[i].t;
  }
  return INFINITY;
}

}  // namespace

TEST(QuarterCarStepTest, RunsToTheEndWithoutFault) {
  EXPECT_EQ(with_friction().result.final_state, RigState::kStopped);
  EXPECT_EQ(with_friction().result.ticks, 8400);
}

TEST(QuarterCarStepTest, TracksTheFilteredStepsAndIntegralActionRemovesTheError) {
  const StepRun& run = with_friction();
  double peak_error = 0.0;
  for (const auto& k : run.ticks) peak_error = std::max(peak_error, std::abs(k.x_ref - k.x_r));
  // docs/rig-models.md 1.7: peak error 6-7 mm during a 50 mm step.
  std::printf("peak tracking error %.2f mm\n", peak_error * 1e3);
  EXPECT_GT(peak_error, 0.004);
  EXPECT_LT(peak_error, 0.009);
  for (int i = 0; i < kSteps; ++i) {
    const double t_step = kFirstStep + i * kStepHold;
    // 1 s after the step the 0.25 s demand filter has 1.8 % (0.9 mm) left;
    // the loop must be within 2 mm of the demand.
    EXPECT_LT(std::abs(run.at(t_step + 1.0).x_ref - run.at(t_step + 1.0).x_r), 0.002) << "step " << i;
    // By the end of the hold the integral action has brought the error to a
    // small remainder (the paper's "small steady state error"): below 1 mm,
    // averaged over 0.25 s to see through the LVDT noise.
    double mean_error = 0.0;
    for (int k = 0; k < 100; ++k) {
      const auto& s = run.at(t_step + kStepHold - 0.25 + k * 0.0025);
      mean_error += (s.x_ref - s.x_r) / 100.0;
    }
    EXPECT_LT(std::abs(mean_error), 0.001) << "step " << i;
  }
}

TEST(QuarterCarStepTest, LeakageNeedsAValveOffsetThatOnlyTheIntegralSupplies) {
  // At rest under leakage the valve must sit near u0 = -0.043; with e ~ 0 the
  // P part is ~0, so that offset is the integrator's.
  const StepRun& run = with_friction();
  const double u0 = QuarterCarPlant::rest_valve_offset(run.config.quarter_car);
  double mean_u = 0.0;
  for (int k = 0; k < 200; ++k) mean_u += run.at(20.4 + k * 0.0025).u / 200.0;
  EXPECT_NEAR(mean_u, u0, 0.03);
  EXPECT_LT(mean_u, -0.01);
}

TEST(QuarterCarStepTest, ChamberPressuresStayWithinTankAndSupply) {
  for (const StepRun* run : {&with_friction(), &without_friction()}) {
    const double ps = run->config.quarter_car.supply_pressure;
    for (const auto& k : run->ticks) {
      ASSERT_GE(k.truth.p1, run->config.quarter_car.cavitation_pressure);
      ASSERT_LE(k.truth.p1, ps);
      ASSERT_GE(k.truth.p2, run->config.quarter_car.cavitation_pressure);
      ASSERT_LE(k.truth.p2, ps);
      // Measured through 0..250 bar transducers: within 0..Ps up to noise.
      ASSERT_GE(k.p1, 0.0);
      ASSERT_LE(k.p1, ps + 1e5);
    }
  }
}

TEST(QuarterCarStepTest, BodyStaysStillWhileTheWheelStartsToMoveOnlyWithFriction) {
  // Steps that start from rest (the body has had 4 s to settle).
  for (int i = 1; i < kSteps; ++i) {
    const double t_step = kFirstStep + i * kStepHold;
    const auto x_w = [](const Tick& k) { return k.x_w; };
    const auto x_b = [](const Tick& k) { return k.x_b; };
    // 0.5 mm is 16 standard deviations of the LVDT noise: a real movement.
    const double lag_friction = departure_time(with_friction(), t_step, 5e-4, x_b) -
                                departure_time(with_friction(), t_step, 5e-4, x_w);
    const double lag_free = departure_time(without_friction(), t_step, 5e-4, x_b) -
                            departure_time(without_friction(), t_step, 5e-4, x_w);
    // With friction the body waits until the spring force reaches breakaway
    // (~200 N = ks x 6.9 mm of wheel travel, Fig. 7 and 10 of the paper).
    std::printf("step %d lag friction %.3f s, free %.3f s\n", i, lag_friction, lag_free);
    EXPECT_GT(lag_friction, 0.06) << "step " << i;
    EXPECT_GT(lag_friction, lag_free + 0.03) << "step " << i;
    // And it truly stands still: the true body velocity is exactly zero then.
    const StepRun& run = with_friction();
    const double wheel_moves = departure_time(run, t_step, 5e-4, x_w);
    EXPECT_TRUE(run.at(wheel_moves).stuck) << "step " << i;
    EXPECT_EQ(run.at(wheel_moves).truth.v_b, 0.0) << "step " << i;
    // Without friction the body is already moving when the wheel has moved.
    EXPECT_NE(without_friction().at(wheel_moves).truth.v_b, 0.0) << "step " << i;
  }
}

TEST(QuarterCarStepTest, FrictionAgainstBodyVelocityShowsStictionPeakAndStribeckDip) {
  const StepRun& run = with_friction();
  const auto& f = run.config.quarter_car.bearing_friction;
  // Stiction: while stuck, the bearing carries the applied force, up to
  // breakaway just before each break-away.
  double stuck_peak = 0.0;
  std::vector<double> slow, fast;  // |F| while sliding at low and at moderate speed
  for (const auto& k : run.ticks) {
    const double v = std::abs(k.truth.v_b);
    if (k.stuck) stuck_peak = std::max(stuck_peak, std::abs(k.f_bearing));
    else if (v < 0.2 * f.stribeck_velocity) slow.push_back(std::abs(k.f_bearing));
    else if (v > 2.0 * f.stribeck_velocity && v < 6.0 * f.stribeck_velocity) fast.push_back(std::abs(k.f_bearing));
  }
  ASSERT_GT(slow.size(), 10u);
  ASSERT_GT(fast.size(), 10u);
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  // Breakaway is F_c0 + mu F_n + dF_s ~ 200 N; the Stribeck excess dF_s
  // (100 N) has decayed by 2 v_s (exp(-4)), while viscous adds only D v.
  std::printf("stuck peak %.1f N, slow median %.1f N, fast median %.1f N\n", stuck_peak, median(slow), median(fast));
  EXPECT_GT(stuck_peak, 150.0);
  EXPECT_GT(median(slow) - median(fast), 0.5 * f.stiction_excess) << "Stribeck dip";
  EXPECT_GT(median(fast), f.coulomb_base) << "Coulomb level remains";
  // Without friction there is no bearing force at all.
  for (const auto& k : without_friction().ticks) ASSERT_EQ(k.f_bearing, 0.0);
}

TEST(QuarterCarStepTest, BodyOscillationDecaysFasterWithFriction) {
  // Ring-down of the body about its final position after each step, from
  // 1 s to 4 s after the step (the 1.75 Hz body mode, damping ratio 0.049
  // from the damper alone).
  const auto ring = [](const StepRun& run) {
    double sum = 0.0;
    int n = 0;
    for (int i = 0; i < kSteps; ++i) {
      const double t_step = kFirstStep + i * kStepHold;
      const double final_x = run.at(t_step + kStepHold - 0.01).truth.x_b;
      for (double t = t_step + 1.0; t < t_step + kStepHold; t += 0.0025) {
        const double d = run.at(t).truth.x_b - final_x;
        sum += d * d;
        ++n;
      }
    }
    return std::sqrt(sum / n);
  };
  const double with = ring(with_friction()), without = ring(without_friction());
  std::printf("ring-down rms with %.3g m, without %.3g m\n", with, without);
  EXPECT_LT(with, 0.3 * without) << "rms ring-down with friction " << with << " m, without " << without << " m";
}
