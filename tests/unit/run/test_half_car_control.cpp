// Passive vs fuzzy (seed 001) vs skyhook vs LQR active suspension on the
// paper's bump, closed loop through the real loop (RigLoop, 2.5 ms,
// VirtualClock), the simulated driver with sensor noise, and the half-car
// plant. Regulation: setpoint 0, the road is the disturbance. Metrics are
// computed from the plant's true signals.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "drivers/sim/sim_driver.hpp"
#include "plant/half_car/half_car_plant.hpp"
#include "rt/control/fuzzy_suspension_controller.hpp"
#include "rt/control/lqr_controller.hpp"
#include "rt/loop/rig_loop.hpp"
#include "rt/control/skyhook_controller.hpp"
#include "tests/support/plausibility_detectors.hpp"
#include "tools/suspension/suspension_metrics.hpp"

using namespace rigctl;
namespace sig = half_car_signal;

namespace {

constexpr double kPeriod = 0.0025;
constexpr double kDuration = 10.0;
constexpr double kForceLimit = kDefaultSuspensionForceLimit;

using Signals = std::array<double, sig::kCount>;

struct Recorded {
  std::vector<Signals> truth;
  std::vector<std::array<double, 2>> command;
  LoopResult result;
  SuspensionRun run;
  SuspensionMetrics metrics;          // settling band: see paper_bump()
  SuspensionMetrics metrics_own_band; // settling band 5 % of the run's own peak
};

// Records the plant's true signals and the loop's command on every tick.
class RecordingSink final : public TelemetrySink {
 public:
  explicit RecordingSink(const HalfCarPlant& plant) : plant_(plant) {
    truth.reserve(5000);
    command.reserve(5000);
  }
  bool push(const TelemetryRecord& r) noexcept override {
    if (!r.has_sample) return true;
    Signals s;
    plant_.measure(s);
    truth.push_back(s);
    command.push_back({r.command.value[0], r.command.value[1]});
    return true;
  }
  std::vector<Signals> truth;
  std::vector<std::array<double, 2>> command;

 private:
  const HalfCarPlant& plant_;
};

// Modest transducer noise (1 sigma): LVDTs 0.1 mm, angle 0.1 mrad,
// velocity 1-2 mm/s, accelerometers 0.02 m/s^2; truth channels exact.
std::vector<SensorSpec> sensors() {
  std::vector<SensorSpec> s(sig::kCount);
  for (std::size_t i : {sig::kZr1, sig::kZr2, sig::kZs, sig::kZu1, sig::kZu2, sig::kTravel1, sig::kTravel2}) {
    s[i].noise_sd = 1e-4;
  }
  s[sig::kPhi].noise_sd = 1e-4;
  s[sig::kZsDot].noise_sd = 1e-3;
  s[sig::kPhiDot].noise_sd = 1e-3;
  s[sig::kZu1Dot].noise_sd = s[sig::kZu2Dot].noise_sd = 2e-3;
  s[sig::kZsDdot].noise_sd = 0.02;
  s[sig::kPhiDdot].noise_sd = 0.02;
  return s;
}

Recorded run_closed_loop(Controller& controller, const HalfCarParams& params, double duration = kDuration) {
  auto plant = std::make_unique<HalfCarPlant>(params);
  const HalfCarPlant& plant_ref = *plant;
  SimDriver driver(std::move(plant), sensors(), std::vector<SensorSpec>(2), kPeriod, 1, {0.0, 0.0});
  RecordingSink sink(plant_ref);
  FilteredProfile profile(std::make_unique<TableProfile>(std::vector<double>{0.0, duration}, std::vector<double>{0.0, 0.0}),
                          0.0, kPeriod);
  VirtualClock clock;
  LoopOptions options;
  options.max_ticks = std::lround(duration / kPeriod);
  driver.start();
  // As `rigctl run` runs config/half_car.yaml: the automatic sequence arms
  // on the measured body heave and holds it at 0 while the road moves under it.
  SafetyOptions safety;
  safety.feedback_input = static_cast<int>(sig::kZs);
  safety.machine.hold_deceleration = 1.0;  // [m/s^2]
  safety.machine.setpoint_rate = 0.05;     // [m/s]
  RigLoop loop(driver, controller, profile,
               test::plausibility_detectors(driver.layout().inputs.size(), safety.feedback_input, kPeriod), sink, clock,
               options, safety);
  std::atomic<bool> stop{false};
  Recorded out;
  out.result = loop.run(stop);
  out.truth = std::move(sink.truth);
  out.command = std::move(sink.command);

  SuspensionRun& run = out.run;
  run.dt = kPeriod;
  run.disturbance_start = params.road.bump.start_time;
  for (std::size_t k = 0; k < out.truth.size(); ++k) {
    const auto& s = out.truth[k];
    run.z_s.push_back(s[sig::kZs]);
    run.z_s_ddot.push_back(s[sig::kZsDdot]);
    run.phi.push_back(s[sig::kPhi]);
    run.phi_ddot.push_back(s[sig::kPhiDdot]);
    run.travel[0].push_back(s[sig::kTravel1]);
    run.travel[1].push_back(s[sig::kTravel2]);
    run.tyre_deflection[0].push_back(s[sig::kZr1] - s[sig::kZu1]);
    run.tyre_deflection[1].push_back(s[sig::kZr2] - s[sig::kZu2]);
    run.force[0].push_back(out.command[k][0]);
    run.force[1].push_back(out.command[k][1]);
    run.contact[0].push_back(s[sig::kSimContact1]);
    run.contact[1].push_back(s[sig::kSimContact2]);
  }
  out.metrics = out.metrics_own_band = compute_suspension_metrics(run);
  return out;
}

struct Comparison {
  Recorded passive, fuzzy, fuzzy_odd, skyhook, lqr;
};

const Comparison& paper_bump() {
  static const Comparison c = [] {
    const HalfCarParams p;  // pitch plane, paper's bump
    Comparison r;
    PassiveSuspensionController passive;
    r.passive = run_closed_loop(passive, p);
    FuzzySuspensionConfig fc;
    fc.engine = paper_fuzzy_spec({0.10, 4.0, kForceLimit});
    fc.force_limit = kForceLimit;
    FuzzySuspensionController fuzzy(fc);
    r.fuzzy = run_closed_loop(fuzzy, p);
    fc.engine = paper_fuzzy_spec({0.10, 4.0, kForceLimit}, PaperRuleTable::kOddSymmetric);
    FuzzySuspensionController fuzzy_odd(fc);
    r.fuzzy_odd = run_closed_loop(fuzzy_odd, p);
    SkyhookController sky{SkyhookConfig{}};
    r.skyhook = run_closed_loop(sky, p);
    LqrController lqr(LqrConfig::from_design(p, LqrWeights{}, kForceLimit));
    r.lqr = run_closed_loop(lqr, p);

    // Settling is timed to one band for every controller: 5 % of the
    // passive run's peak body displacement (0.17 mm). 5 % of each run's own
    // peak would put the band of the active runs (peaks ~1.4 mm: 0.07 mm)
    // below the body LVDT's 0.1 mm noise, and the noise-driven wander of
    // the body under the high-gain fuzzy law (+-0.05 mm) would then decide
    // the result; both definitions are printed.
    SettlingSpec common;
    common.fraction = 0.0;
    common.min_band = 0.05 * r.passive.metrics_own_band.peak_z_s;
    for (Recorded* x : {&r.passive, &r.fuzzy, &r.fuzzy_odd, &r.skyhook, &r.lqr}) {
      x->metrics = compute_suspension_metrics(x->run, common);
    }
    std::printf("\nPaper's bump (a0 0.05 m, lambda0 0.2 m, V 20 m/s, two humps), pitch plane, force limit %.0f N\n",
                kForceLimit);
    std::printf("settling band +-%.3f mm (5 %% of the passive peak); with 5 %% of each run's own peak: passive %.3f s, "
                "fuzzy %.3f s, fuzzy-odd %.3f s, skyhook %.3f s, lqr %.3f s\n",
                common.min_band * 1e3, r.passive.metrics_own_band.settling_time, r.fuzzy.metrics_own_band.settling_time,
                r.fuzzy_odd.metrics_own_band.settling_time, r.skyhook.metrics_own_band.settling_time,
                r.lqr.metrics_own_band.settling_time);
    std::printf("%s", format_metrics_table({"passive", "fuzzy", "fuzzy-odd", "skyhook", "lqr"},
                                           {r.passive.metrics, r.fuzzy.metrics, r.fuzzy_odd.metrics, r.skyhook.metrics,
                                            r.lqr.metrics})
                          .c_str());
    auto line = [&](const char* what, double paper, auto get) {
      std::printf("%-34s paper %6s  fuzzy %7.1f %%  fuzzy-odd %7.1f %%  skyhook %7.1f %%  lqr %7.1f %%\n", what,
                  paper > 0 ? (std::to_string(paper).substr(0, 5) + " %").c_str() : "   -  ",
                  reduction_percent(get(r.passive.metrics), get(r.fuzzy.metrics)),
                  reduction_percent(get(r.passive.metrics), get(r.fuzzy_odd.metrics)),
                  reduction_percent(get(r.passive.metrics), get(r.skyhook.metrics)),
                  reduction_percent(get(r.passive.metrics), get(r.lqr.metrics)));
    };
    using M = SuspensionMetrics;
    std::printf("Reductions vs passive (positive = smaller than passive):\n");
    line("peak body displacement", 74.2, [](const M& m) { return m.peak_z_s; });
    line("peak body acceleration", 88.72, [](const M& m) { return m.peak_acc; });
    line("RMS body acceleration", 0.0, [](const M& m) { return m.rms_acc; });
    line("Wk RMS body acceleration (LQR)", 82.6, [](const M& m) { return m.wk_rms_acc; });
    line("peak tyre deflection (worse corner)", 28.5,
         [](const M& m) { return std::max(m.peak_tyre_deflection[0], m.peak_tyre_deflection[1]); });
    line("peak suspension travel (worse)", 0.0, [](const M& m) { return std::max(m.peak_travel[0], m.peak_travel[1]); });
    line("settling time (paper 6 -> 3.5 s)", 41.7, [](const M& m) { return m.settling_time; });
    line("peak jerk", 0.0, [](const M& m) { return m.peak_jerk; });
    line("peak pitch angle", 0.0, [](const M& m) { return m.peak_phi; });
    line("peak pitch acceleration", 0.0, [](const M& m) { return m.peak_phi_ddot; });
    return r;
  }();
  return c;
}

double max_abs_command(const Recorded& r) {
  double m = 0.0;
  for (const auto& c : r.command) m = std::max({m, std::abs(c[0]), std::abs(c[1])});
  return m;
}

}  // namespace

TEST(HalfCarControl, EveryRunCompletesWithoutFault) {
  const Comparison& c = paper_bump();
  for (const Recorded* r : {&c.passive, &c.fuzzy, &c.fuzzy_odd, &c.skyhook, &c.lqr}) {
    EXPECT_EQ(r->result.final_state, RigState::kStopped);
    EXPECT_EQ(r->result.ticks, 4000);
    EXPECT_TRUE(r->metrics.settled);
  }
}

TEST(HalfCarControl, FuzzyReducesPeakDisplacementPeakAccelerationAndSettlingTime) {
  const Comparison& c = paper_bump();
  const auto& p = c.passive.metrics;
  const auto& f = c.fuzzy.metrics;
  EXPECT_LT(f.peak_z_s, p.peak_z_s);
  EXPECT_LT(f.peak_acc, p.peak_acc);
  EXPECT_LT(f.settling_time, p.settling_time);
}

TEST(HalfCarControl, LqrReducesRmsBodyAcceleration) {
  const Comparison& c = paper_bump();
  EXPECT_LT(c.lqr.metrics.rms_acc, c.passive.metrics.rms_acc);
  EXPECT_LT(c.lqr.metrics.wk_rms_acc, c.passive.metrics.wk_rms_acc);
}

TEST(HalfCarControl, ActuatorForcesStayWithinTheirLimit) {
  const Comparison& c = paper_bump();
  EXPECT_EQ(max_abs_command(c.passive), 0.0);
  for (const Recorded* r : {&c.fuzzy, &c.fuzzy_odd, &c.skyhook, &c.lqr}) {
    EXPECT_LE(max_abs_command(*r), kForceLimit);
    EXPECT_GT(max_abs_command(*r), 0.0);
    // The plant applied what was commanded (ideal actuator, no lag).
    double applied = 0.0;
    for (const auto& s : r->truth) applied = std::max({applied, std::abs(s[sig::kSimFAct1]), std::abs(s[sig::kSimFAct2])});
    EXPECT_LE(applied, kForceLimit);
  }
}

TEST(HalfCarControl, TyresKeepContactOnThePapersBump) {
  const Comparison& c = paper_bump();
  const char* names[] = {"passive", "fuzzy", "fuzzy-odd", "skyhook", "lqr"};
  int i = 0;
  for (const Recorded* r : {&c.passive, &c.fuzzy, &c.fuzzy_odd, &c.skyhook, &c.lqr}) {
    double least[2] = {1e9, 1e9};
    for (const auto& s : r->truth) {
      least[0] = std::min(least[0], s[sig::kSimTyreForce1]);
      least[1] = std::min(least[1], s[sig::kSimTyreForce2]);
    }
    std::printf("%-10s least tyre load front %6.0f N, rear %6.0f N\n", names[i++], least[0], least[1]);
    EXPECT_EQ(r->metrics.time_without_contact[0], 0.0);
    EXPECT_EQ(r->metrics.time_without_contact[1], 0.0);
  }
}

TEST(HalfCarControl, RandomRoadAndCurveRunsForTheRecord) {
  // Not asserted beyond sanity: ISO 8608 class C at 20 m/s and the roll
  // plane in a 100 m curve, for the report.
  HalfCarParams p;
  p.road.kind = RoadKind::kIso8608;
  p.road.iso.road_class = IsoRoadClass::kC;
  p.road.bump.start_time = 0.0;
  PassiveSuspensionController passive;
  FuzzySuspensionController fuzzy{FuzzySuspensionConfig{}};
  SkyhookController sky{SkyhookConfig{}};
  LqrController lqr(LqrConfig::from_design(p));
  std::vector<SuspensionMetrics> m;
  for (Controller* c : std::initializer_list<Controller*>{&passive, &fuzzy, &sky, &lqr}) {
    m.push_back(run_closed_loop(*c, p, 20.0).metrics);
  }
  std::printf("\nISO 8608 class C, 20 m/s, 20 s, pitch plane\n%s",
              format_metrics_table({"passive", "fuzzy", "skyhook", "lqr"}, m).c_str());
  for (const auto& x : m) EXPECT_TRUE(std::isfinite(x.rms_acc));

  // The single-hump reading of eq. 9 (0 <= t <= lambda0 / V).
  HalfCarParams one = HalfCarParams{};
  one.road.bump.cycles = 1.0;
  std::vector<Recorded> rec1;
  for (Controller* c : std::initializer_list<Controller*>{&passive, &fuzzy, &sky, &lqr}) {
    rec1.push_back(run_closed_loop(*c, one));
  }
  SettlingSpec common;  // as for the paper's bump: 5 % of the passive peak for every run
  common.fraction = 0.0;
  common.min_band = 0.05 * rec1[0].metrics.peak_z_s;
  std::vector<SuspensionMetrics> m1;
  for (const auto& x : rec1) m1.push_back(compute_suspension_metrics(x.run, common));
  std::printf("\nSingle hump (cycles = 1), pitch plane\n%s",
              format_metrics_table({"passive", "fuzzy", "skyhook", "lqr"}, m1).c_str());

  HalfCarParams r = HalfCarParams::roll_plane();
  SkyhookConfig sc;
  sc.lever_arm = {0.5 * r.track, -0.5 * r.track};
  SkyhookController sky_roll(sc);
  FuzzySuspensionConfig fc;
  fc.lever_arm = sc.lever_arm;
  FuzzySuspensionController fuzzy_roll(fc);
  std::vector<SuspensionMetrics> mr;
  for (Controller* c : std::initializer_list<Controller*>{&passive, &fuzzy_roll, &sky_roll}) {
    const Recorded rec = run_closed_loop(*c, r, 5.0);
    mr.push_back(rec.metrics);
  }
  std::printf("\nRoll plane, 100 m curve at 20 m/s from 0.5 s (steady roll 36 mrad passive)\n%s",
              format_metrics_table({"passive", "fuzzy", "skyhook"}, mr).c_str());
}
