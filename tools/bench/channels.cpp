// Channels section: the cost of one RigLoop tick against its number of
// control channels (issue 31 item 1). Two rigs, both whole RigLoop runs in
// simulated time (wait is free, so the wall time per tick is the tick's
// compute: read, check, commands, demand, control, write, hand-off):
//   * the loop alone, 1, 2, 4 and 8 channels on a driver with no plant
//     (rods that integrate their valve commands), each channel a PI with its
//     own ramp profile and a range detector on its input;
//   * the shipped two-poster (config/half_car_two_poster.yaml): 2 channels
//     with the simulated plant (RK4, 20 sub-steps per period) and sensors.
// The best of several runs: the machine is shared, and the best is the
// tick's own cost.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "rt/control/pi_controller.hpp"
#include "rt/loop/rig_loop.hpp"
#include "tools/bench/sections.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl::bench {

namespace {

constexpr double kT = 0.0025;

// N rods, rod i moving at 0.5 x its command [m/s].
class Rods final : public Driver {
 public:
  explicit Rods(std::size_t n) : n_(n) {
    for (std::size_t i = 0; i < n; ++i) {
      layout_.inputs.push_back({"x_" + std::to_string(i + 1), "m"});
      layout_.outputs.push_back({"u_" + std::to_string(i + 1), "1"});
    }
  }
  const ChannelLayout& layout() const override { return layout_; }
  void start() override {
    x_.fill(0.0);
    u_.fill(0.0);
    reads_ = 0;
  }
  bool read(Sample& out) override {
    for (std::size_t i = 0; i < n_; ++i) out.value[i] = x_[i] += u_[i] * 0.5 * kT;
    out.t_ns = reads_++ * 2'500'000;
    return true;
  }
  void write(const Command& c) override { std::copy_n(c.value.begin(), n_, u_.begin()); }
  void make_safe() noexcept override { u_.fill(0.0); }
  void stop() override {}

 private:
  std::size_t n_;
  ChannelLayout layout_;
  std::array<double, kMaxOutputs> x_{}, u_{};
  int64_t reads_ = 0;
};

class CountingSink final : public TelemetrySink {
 public:
  bool push(const TelemetryRecord& r) noexcept override {
    last_u += r.command.value[0];  // read the record, so the copy is not optimised away
    ++records;
    return true;
  }
  int64_t records = 0;
  double last_u = 0.0;
};

struct Measured {
  double best_ns_per_tick = std::numeric_limits<double>::infinity();
  int64_t ticks = 0;
};

LoopOptions options(int64_t ticks) {
  LoopOptions o;
  o.period_ns = 2'500'000;
  o.max_ticks = ticks;
  o.timing_every_ticks = 400;
  return o;
}

// One run of `loop`'s rig; wall time per handed-off tick.
template <class MakeLoop>
Measured best_of(int repetitions, MakeLoop&& run_once) {
  Measured m;
  for (int r = 0; r < repetitions; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const int64_t ticks = run_once();
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
    m.ticks = ticks;
    m.best_ns_per_tick = std::min(m.best_ns_per_tick, ns / static_cast<double>(std::max<int64_t>(1, ticks)));
  }
  return m;
}

Measured loop_alone(std::size_t n, int64_t ticks, int repetitions) {
  Rods driver(n);
  std::vector<std::unique_ptr<PiController>> pis;
  std::vector<std::unique_ptr<FilteredProfile>> profiles;
  std::vector<DetectorSpec> specs;
  for (std::size_t i = 0; i < n; ++i) {
    PiConfig c;
    c.kp = 20.0;
    c.period_s = kT;
    c.feedback_input = static_cast<int>(i);
    c.output_index = static_cast<int>(i);
    pis.push_back(std::make_unique<PiController>(c));
    const double target = 0.01 * static_cast<double>(i + 1);
    profiles.push_back(std::make_unique<FilteredProfile>(
        std::make_unique<RampStepsProfile>(LeadIn{0.0, target, 0.1, 0.02}, std::vector<double>{0.01, 0.0}, 1.0),
        0.05, kT));
    DetectorSpec range;
    range.name = "limits.x_" + std::to_string(i + 1);
    range.kind = DetectorKind::kRange;
    range.channel = static_cast<int>(i);
    range.min = -1.0;
    range.max = 1.0;
    specs.push_back(range);
  }
  std::vector<ControlChannel> more;
  for (std::size_t i = 1; i < n; ++i) more.push_back({pis[i].get(), profiles[i].get(), static_cast<int>(i)});
  return best_of(repetitions, [&] {
    driver.start();
    CountingSink sink;
    VirtualClock clock;
    SafetyOptions s;
    s.feedback_input = 0;
    RigLoop loop(driver, *pis[0], *profiles[0], LimitDetectors(specs, n, 0, kT), sink, clock, options(ticks), s);
    loop.set_more_channels(more);
    const std::atomic<bool> never{false};
    return loop.run(never).ticks;
  });
}

Measured two_poster(const RigConfig& config, int64_t ticks, int repetitions) {
  return best_of(repetitions, [&] {
    AssembledRig rig = assemble_rig(config);
    rig.driver->start();
    CountingSink sink;
    VirtualClock clock;
    LoopOptions o = options(ticks);
    o.start_from_input = rig.profile_start_input;
    RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, sink, clock, o, rig.safety);
    loop.set_more_channels(rig.more_channels);
    const std::atomic<bool> never{false};
    const int64_t n = loop.run(never).ticks;
    rig.driver->stop();
    return n;
  });
}

}  // namespace

Section channels_section() {
  return {"channels", "channels: one RigLoop tick against its control channels (simulated time, best of runs)",
          [](Context& ctx) {
            const int64_t ticks = ctx.pick<int64_t>(4000, 400);  // 10 s of rig time, 1 s quick
            const int repetitions = ctx.pick(7, 2);
            Json j = Json::object();
            j["what"] = "wall time per tick of whole RigLoop runs in simulated time (read, check, commands, demand, control, write, hand-off to a counting sink), best of the repetitions";
            j["ticks_per_run"] = ticks;
            j["repetitions"] = repetitions;
            Table t({"rig", "channels", "ns per tick", "of 2.5 ms period", "ticks"});
            Json alone = Json::object();
            for (const std::size_t n : {std::size_t{1}, std::size_t{2}, std::size_t{4}, std::size_t{8}}) {
              const Measured m = loop_alone(n, ticks, repetitions);
              Json e = Json::object();
              e["channels"] = static_cast<int64_t>(n);
              e["ns_per_tick"] = m.best_ns_per_tick;
              e["ticks"] = m.ticks;
              alone["channels:" + std::to_string(n)] = e;
              t.row({"loop alone (no plant)", std::to_string(n), fmt("%.0f", m.best_ns_per_tick),
                     fmt("%.4f%%", 100.0 * m.best_ns_per_tick * 1e-9 / kT), std::to_string(m.ticks)});
            }
            j["loop_alone"] = alone;
            const std::string tp_path = ctx.options.config_dir + "/half_car_two_poster.yaml";
            const Measured tp = two_poster(load_rig_config(tp_path), ticks, repetitions);
            Json e = Json::object();
            e["config"] = "config/half_car_two_poster.yaml";
            e["channels"] = 2;
            e["ns_per_tick"] = tp.best_ns_per_tick;
            e["ticks"] = tp.ticks;
            j["two_poster"] = e;
            t.row({"two_poster (plant, sensors)", "2", fmt("%.0f", tp.best_ns_per_tick),
                   fmt("%.4f%%", 100.0 * tp.best_ns_per_tick * 1e-9 / kT), std::to_string(tp.ticks)});
            ctx.out << t.text("    ");
            return j;
          }};
}

}  // namespace rigctl::bench
