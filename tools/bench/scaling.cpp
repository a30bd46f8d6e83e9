// Scaling section (Google Benchmark): how the cost of one plant period grows
// with the RK4 sub-steps, and how the tick (read, limit detectors, demand,
// controller, write: what RigLoop times as compute) grows with the number of
// servo-hydraulic actuators, each a quarter-car post with its own PI loop
// (1, 2, 4, 8: quarter car, two-post half car, four-poster, two four-posters).
// One RigLoop cannot hold 8 actuators (rt/sample.hpp: 24 inputs, 4
// outputs), so the tick here runs the same steps over N assembled rigs,
// each running the 20 s step test of config/quarter_car.yaml over and over.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <span>

#include "config/rig_config.hpp"
#include "plant/quarter_car/quarter_car_step_size.hpp"
#include "tools/bench/sections.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl::bench {

namespace {

struct Measured {
  double ns_per_iteration = 0.0;
  int64_t iterations = 0;
};

class CollectingReporter final : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context&) override { return true; }
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs) {
      if (r.error_occurred || r.run_type != Run::RT_Iteration) continue;
      double t = r.GetAdjustedRealTime();
      switch (r.time_unit) {
        case benchmark::kNanosecond: break;
        case benchmark::kMicrosecond: t *= 1e3; break;
        case benchmark::kMillisecond: t *= 1e6; break;
        case benchmark::kSecond: t *= 1e9; break;
      }
      // The name carries the settings too ("NAME/min_time:0.500"): keep NAME.
      std::string name = r.benchmark_name();
      const auto cut = name.find("/min_time:");
      if (cut != std::string::npos) name.erase(cut);
      results[name] = {t, static_cast<int64_t>(r.iterations)};
    }
  }
  std::map<std::string, Measured> results;
};

void initialise_google_benchmark() {
  static bool done = false;
  if (done) return;
  int argc = 1;
  char name[] = "rigctl-bench";
  char* argv[] = {name, nullptr};
  benchmark::Initialize(&argc, argv);
  done = true;
}

// One post of a multi-actuator rig: the parts assemble_rig makes.
struct Post {
  AssembledRig rig;
  Sample sample;
  Command command;
  ControllerTerms terms;
  // What acted until this tick: the detectors judge the sample against it.
  Command previous_command;
  double previous_demand = 0.0;
  int64_t tick = 0;
};

// RigLoop's check: the configured detectors on this tick's sample (a trip
// only counts here; a restart of the step test may look like a jump to them).
bool check_limits(Post& p) noexcept {
  DetectorInputs in;
  in.sample = &p.sample;
  in.now_ns = p.sample.t_ns;
  in.demand = p.previous_demand;
  in.command = &p.previous_command;
  in.valve_driven = true;
  return p.rig.detectors.check(in).new_count == 0;
}

struct PlantBenchmark {
  std::string name;   // Google Benchmark's
  std::string plant;
  int substeps = 0;
};

// One benchmark per plant and sub-steps (1/4..4x the plant's own): advance()
// over one period, on the recorded commands; they read `in`, which must
// outlive their run.
std::vector<PlantBenchmark> register_plant_benchmarks(const PlantInputs& in, double min_time) {
  struct PlantCase {
    std::string name;
    int default_substeps;
    std::function<std::unique_ptr<SimulatedPlant>(int)> make;
    const CommandSeries* u;
  };
  const std::vector<PlantCase> plants = {
      {"quarter_car", quarter_car_substeps(in.qc.quarter_car, in.qc.loop.period_s),
       [&in](int n) {
         QuarterCarParams p = in.qc.quarter_car;
         p.substeps = n;
         return std::unique_ptr<SimulatedPlant>(new QuarterCarPlant(p));
       },
       &in.qc_u},
      {"pneumatic_rotary", in.pn.pneumatic_rotary.substeps,
       [&in](int n) {
         PneumaticRotaryParams p = in.pn.pneumatic_rotary;
         p.substeps = n;
         return std::unique_ptr<SimulatedPlant>(new PneumaticRotaryPlant(p));
       },
       &in.pn_u},
      {"half_car_bump", in.bump.substeps,
       [&in](int n) {
         HalfCarParams p = in.bump;
         p.substeps = n;
         return std::unique_ptr<SimulatedPlant>(new HalfCarPlant(p));
       },
       &in.passive},
  };
  const double T = in.T;
  std::vector<PlantBenchmark> registered;
  for (const auto& pc : plants) {
    for (const double m : {0.25, 0.5, 1.0, 2.0, 4.0}) {
      const int n = std::max(1, static_cast<int>(std::lround(pc.default_substeps * m)));
      const std::string name = "plant/" + pc.name + "/substeps:" + std::to_string(n);
      const CommandSeries* u = pc.u;
      auto make = pc.make;
      benchmark::RegisterBenchmark(name.c_str(),
                                   [make, n, u, T](benchmark::State& state) {
                                     auto plant = make(n);
                                     plant->reset();
                                     const std::size_t nc = plant->commands().size();
                                     std::size_t k = 0;
                                     for (auto _ : state) {
                                       plant->advance(std::span<const double>((*u)[k].data(), nc), T);
                                       if (++k == u->size()) {
                                         k = 0;
                                         plant->reset();
                                       }
                                     }
                                   })
          ->MinTime(min_time)
          ->Unit(benchmark::kNanosecond);
      registered.push_back({name, pc.name, n});
    }
  }
  return registered;
}

// `posts` quarter-car posts, each its own assembled rig (seeds apart), started.
std::vector<std::unique_ptr<Post>> make_posts(const RigConfig& qc, int posts) {
  std::vector<std::unique_ptr<Post>> rig;
  for (int i = 0; i < posts; ++i) {
    auto p = std::make_unique<Post>();
    RigConfig c = qc;
    c.seed = qc.seed + static_cast<uint64_t>(i);
    p->rig = assemble_rig(c);
    p->rig.driver->start();
    p->rig.controller->reset();
    p->rig.profile->reset();
    rig.push_back(std::move(p));
  }
  return rig;
}

// RigLoop's tick body, for every post; counts the faults.
void tick_posts(std::vector<std::unique_ptr<Post>>& rig, int64_t run_ticks, int64_t& faults) {
  for (auto& p : rig) {
    AssembledRig& r = p->rig;
    if (!r.driver->read(p->sample)) ++faults;
    if (!check_limits(*p)) ++faults;
    if (p->tick == 0 && r.profile_start_input >= 0) {
      r.profile->start_from(p->sample.value[static_cast<std::size_t>(r.profile_start_input)]);
    }
    const double sp = r.profile->next(static_cast<double>(p->sample.t_ns) * 1e-9);
    r.controller->update(sp, p->sample, p->command, p->terms);
    r.driver->write(p->command);
    p->previous_command = p->command;
    p->previous_demand = sp;
    if (++p->tick == run_ticks) {
      // The 20 s step test again, as the plant benchmarks
      // replay it: a held rig would be cheaper to simulate.
      r.driver->start();
      r.controller->reset();
      r.profile->reset();
      p->tick = 0;
    }
  }
}

// One benchmark per count of actuators: the tick over that many posts.
void register_tick_benchmarks(const RigConfig& qc, int64_t ticks, const std::vector<int>& posts_list, double min_time) {
  for (const int posts : posts_list) {
    const std::string name = "tick/actuators:" + std::to_string(posts);
    benchmark::RegisterBenchmark(name.c_str(),
                                 [&qc, posts, run_ticks = ticks](benchmark::State& state) {
                                   std::vector<std::unique_ptr<Post>> rig = make_posts(qc, posts);
                                   int64_t faults = 0;
                                   for (auto _ : state) tick_posts(rig, run_ticks, faults);
                                   state.counters["faults"] = static_cast<double>(faults);
                                 })
        ->MinTime(min_time)
        ->Unit(benchmark::kNanosecond);
  }
}

Json plant_results(const CollectingReporter& reporter, const std::vector<PlantBenchmark>& plant_benchmarks, double T,
                   Table& pt) {
  Json pj = Json::object();
  for (const auto& b : plant_benchmarks) {
    const auto it = reporter.results.find(b.name);
    if (it == reporter.results.end()) continue;
    const double ns = it->second.ns_per_iteration;
    Json e = Json::object();
    e["plant"] = b.plant;
    e["substeps"] = b.substeps;
    e["ns_per_period"] = ns;
    e["ns_per_substep"] = ns / b.substeps;
    e["fraction_of_period"] = ns * 1e-9 / T;
    e["iterations"] = it->second.iterations;
    pj[b.name] = e;
    pt.row({b.plant, std::to_string(b.substeps), fmt("%.2f", ns / 1e3), fmt("%.0f", ns / b.substeps),
            fmt("%.2f%%", 100.0 * ns * 1e-9 / T), std::to_string(it->second.iterations)});
  }
  return pj;
}

Json tick_results(const CollectingReporter& reporter, const std::vector<int>& posts_list, double T, Table& tt) {
  Json tj = Json::object();
  for (const int posts : posts_list) {
    const std::string name = "tick/actuators:" + std::to_string(posts);
    const auto it = reporter.results.find(name);
    if (it == reporter.results.end()) continue;
    const double ns = it->second.ns_per_iteration;
    Json e = Json::object();
    e["actuators"] = posts;
    e["ns_per_tick"] = ns;
    e["ns_per_actuator"] = ns / posts;
    e["fraction_of_period"] = ns * 1e-9 / T;
    e["iterations"] = it->second.iterations;
    tj[name] = e;
    tt.row({std::to_string(posts), fmt("%.2f", ns / 1e3), fmt("%.2f", ns / 1e3 / posts),
            fmt("%.2f%%", 100.0 * ns * 1e-9 / T), std::to_string(it->second.iterations)});
  }
  return tj;
}

Json run_scaling_section(Context& ctx) {
  initialise_google_benchmark();
  const double min_time = ctx.pick(0.5, 0.02);
  const PlantInputs in(ctx, 20.0);
  const double T = in.T;
  const std::vector<PlantBenchmark> plant_benchmarks = register_plant_benchmarks(in, min_time);
  const std::vector<int> posts_list = {1, 2, 4, 8};
  register_tick_benchmarks(in.qc, in.ticks, posts_list, min_time);

  CollectingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::ClearRegisteredBenchmarks();

  Json j = Json::object();
  j["tool"] = "Google Benchmark " + std::string("(library), MinTime ") + fmt("%.2f", min_time) + " s per benchmark, wall time per iteration";
  j["period_s"] = T;
  Table pt({"plant", "substeps", "us per period", "ns per substep", "of 2.5 ms period", "iterations"});
  j["plant_advance"] = plant_results(reporter, plant_benchmarks, T, pt);
  Table tt({"actuators", "us per tick", "per actuator us", "of 2.5 ms period", "iterations"});
  j["tick"] = tick_results(reporter, posts_list, T, tt);
  j["tick_what"] = "per actuator: SimDriver read (plant advance one period + sensor models), limit detectors, demand profile, PI update, DAC write; N quarter-car posts from config/quarter_car.yaml";
  ctx.out << "  plant advance() per control period:\n" << pt.text("    ")
          << "  tick (read to write) against actuators:\n" << tt.text("    ");
  return j;
}

}  // namespace

Section scaling_section() {
  return {"scaling", "scaling: plant cost vs sub-steps, tick time vs actuators (Google Benchmark)", run_scaling_section};
}

}  // namespace rigctl::bench
