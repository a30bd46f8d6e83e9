// BENCHMARK: the tick's compute with a test procedure on it (issue 30:
// compensation, counters, rainflow on two channels, a recovery offered at
// every cycle end) against the config's own profile, on the simulated
// quarter car, paced by the real clock. The runs alternate (profile,
// procedure, profile, procedure, ...) so that a change of the machine's
// load falls on both. docs/benchmarks/procedures.md has measured numbers.
#include <filesystem>
#include <string>
#include <vector>

#include "tools/bench/sections.hpp"

namespace rigctl::bench {

namespace {

double us(int64_t ns) { return static_cast<double>(ns) / 1e3; }

Json run_json(const TimingSummary& t) {
  Json j = Json::object();
  j["ticks"] = t.ticks;
  j["compute_p50_us"] = us(t.compute.p50_ns);
  j["compute_p99_us"] = us(t.compute.p99_ns);
  j["compute_p999_us"] = us(t.compute.p999_ns);
  j["compute_max_us"] = us(t.compute.max_ns);
  const auto demand = static_cast<std::size_t>(TickStage::kDemand);
  const auto hand_off = static_cast<std::size_t>(TickStage::kHandOff);
  j["demand_mean_us"] = t.stages.mean_ns[demand] / 1e3;
  j["demand_max_us"] = us(t.stages.max_ns[demand]);
  j["hand_off_mean_us"] = t.stages.mean_ns[hand_off] / 1e3;
  j["hand_off_max_us"] = us(t.stages.max_ns[hand_off]);
  j["overruns"] = t.overruns;
  return j;
}

}  // namespace

Section procedure_section() {
  return {"procedure", "procedure: tick compute with a test procedure against the profile", [](Context& ctx) {
            const std::string procedure =
                (std::filesystem::path(ctx.quarter_car_config).parent_path() / "quarter_car_procedure.yaml").string();
            const double seconds = ctx.pick(20.0, 4.0);
            const int pairs = ctx.pick(2, 1);
            Json runs = Json::array();
            Table table({"run", "ticks", "compute p50 us", "p99", "p99.9", "max", "demand mean us", "demand max",
                         "hand_off mean", "hand_off max"});
            for (int i = 0; i < pairs && !ctx.stop.load(); ++i) {
              for (const bool with_procedure : {false, true}) {
                const std::string tag = std::string(with_procedure ? "procedure-" : "profile-") + std::to_string(i + 1);
                const LoopRun r = run_loop(ctx, seconds, tag, [&](RunOptions& o) {
                  o.realtime = false;
                  if (with_procedure) {
                    o.procedure_path = procedure;
                    o.recovery_path = ctx.scratch.file(tag + ".recovery");
                  }
                });
                Json j = run_json(r.timing);
                j["run"] = tag;
                runs.push_back(j);
                const TimingSummary& t = r.timing;
                const auto d = static_cast<std::size_t>(TickStage::kDemand);
                const auto h = static_cast<std::size_t>(TickStage::kHandOff);
                table.row({tag, std::to_string(t.ticks), fmt("%.1f", us(t.compute.p50_ns)), fmt("%.1f", us(t.compute.p99_ns)),
                           fmt("%.1f", us(t.compute.p999_ns)), fmt("%.1f", us(t.compute.max_ns)),
                           fmt("%.2f", t.stages.mean_ns[d] / 1e3), fmt("%.1f", us(t.stages.max_ns[d])),
                           fmt("%.2f", t.stages.mean_ns[h] / 1e3), fmt("%.1f", us(t.stages.max_ns[h]))});
                if (ctx.stop.load()) break;
              }
            }
            ctx.out << table.text();
            Json j = Json::object();
            j["status"] = "ok";
            j["seconds_per_run"] = seconds;
            j["procedure"] = procedure;
            j["runs"] = runs;
            return j;
          }};
}

}  // namespace rigctl::bench
