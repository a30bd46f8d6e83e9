// Timing section: wake-up latency of the rigctl loop (the simulated quarter
// car through `rigctl run`'s own code path, paced at the config's period and
// SCHED_FIFO priority) against cyclictest (Debian rt-tests) at the same
// interval and priority, one after the other; idle, then under a CPU load of
// one busy thread per CPU. Each condition is measured three times,
// interleaved (loop, cyclictest, loop, ...), and the ratios are reported as
// median and spread: one run says little on a shared VM. Also the compute
// time of one tick and the steps of the slowest tick.
#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "config/rig_config.hpp"
#include "tools/bench/sections.hpp"
#include "tools/common/stage_text.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl::bench {

namespace {

struct LoopRun {
  TimingSummary timing;
  double wall_s = 0.0;
};

// `rigctl run CONFIG --duration S` in-process, on a thread of its own so the
// SCHED_FIFO priority it takes ends with the thread; the run log goes to the
// scratch directory and is removed.
LoopRun run_loop(Context& ctx, double seconds, const std::string& tag) {
  RunOptions o;
  o.config_path = ctx.quarter_car_config;
  o.duration_s = seconds;
  o.log_path = ctx.scratch.file("loop-" + tag + ".lcm");
  o.lcm_url = "memq://";
  std::ostringstream console;  // the run's own report and status lines
  RunReport report;
  std::exception_ptr error;
  std::thread t([&] {
    try {
      report = run_rig(o, ctx.stop, console);
    } catch (...) {
      error = std::current_exception();
    }
  });
  t.join();
  munlockall();  // run_rig's mlockall is process-wide; the rest of the bench need not stay locked
  std::error_code ec;
  std::filesystem::remove(o.log_path, ec);
  if (error) std::rethrow_exception(error);
  return {report.loop.timing, report.wall_s};
}

struct CyclictestRun {
  Json json;
  std::optional<DistributionSummary> latency;
};

int64_t header_number(const std::string& line) {
  const auto colon = line.find(':');
  if (colon == std::string::npos) return 0;
  std::istringstream in(line.substr(colon + 1));
  int64_t v = 0;
  in >> v;
  return v;
}

CyclictestRun run_cyclictest(Context& ctx, const RealtimeConfig& rt, bool fifo, int64_t period_us, int64_t loops,
                             const std::string& tag) {
  CyclictestRun r;
  r.json = Json::object();
  if (!on_path("cyclictest")) {
    r.json = skipped("cyclictest not found: install Debian package rt-tests");
    return r;
  }
  if (!fifo) {
    // cyclictest refuses to run without the right to real-time scheduling,
    // whatever --policy says.
    r.json = skipped("cyclictest needs SCHED_FIFO, which this process may not use (run as root)");
    return r;
  }
  const std::string hist = ctx.scratch.file("cyclictest-" + tag + ".hist");
  std::vector<std::string> argv = {"cyclictest", "-m", "-q", "-t", "1", "-i", std::to_string(period_us),
                                   "-l", std::to_string(loops), "-h", std::to_string(2 * period_us),
                                   "--histfile=" + hist};
  argv.insert(argv.end(), {"--policy=fifo", "-p", std::to_string(rt.priority)});
  if (rt.cpu >= 0) argv.insert(argv.end(), {"-a", std::to_string(rt.cpu)});
  if (!rt.hold_cpu_dma_latency) argv.push_back("--default-system");
  std::string command;
  for (const auto& a : argv) command += (command.empty() ? "" : " ") + a;
  r.json["command"] = command;

  const double expected_s = static_cast<double>(loops * period_us) * 1e-6;
  const ChildResult child = run_child(argv, ctx.scratch.file("cyclictest-" + tag + ".out"), expected_s + 30.0, ctx.stop);
  r.json["exit_code"] = child.exit_code;
  r.json["wall_s"] = child.wall_s;
  if (!child.started || child.exit_code != 0) {
    std::ifstream log(ctx.scratch.file("cyclictest-" + tag + ".out"));
    std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
    r.json["status"] = "error";
    r.json["error"] = child.error.empty() ? "cyclictest failed: " + text.substr(0, 400) : child.error;
    return r;
  }

  std::ifstream in(hist);
  std::vector<int64_t> counts;
  int64_t overflows = 0, min_us = 0, max_us = 0, avg_us = 0;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("# Min Latencies", 0) == 0) min_us = header_number(line);
    if (line.rfind("# Avg Latencies", 0) == 0) avg_us = header_number(line);
    if (line.rfind("# Max Latencies", 0) == 0) max_us = header_number(line);
    if (line.rfind("# Histogram Overflows", 0) == 0) overflows = header_number(line);
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    int64_t bin = 0, count = 0;
    if (fields >> bin >> count) {
      if (bin >= static_cast<int64_t>(counts.size())) counts.resize(static_cast<std::size_t>(bin + 1), 0);
      counts[static_cast<std::size_t>(bin)] += count;
    }
  }
  const DistributionSummary s = summary_from_us_histogram(counts, overflows, min_us, max_us, static_cast<double>(avg_us));
  if (s.count == 0) {
    r.json["status"] = "error";
    r.json["error"] = "cyclictest wrote no histogram";
    return r;
  }
  r.latency = s;
  r.json["status"] = "ok";
  r.json["wakeup_latency"] = latency_json(s);
  r.json["note"] = "cyclictest's histogram has 1 us bins and whole-us min/max/mean";
  return r;
}

Json fraction_json(const DistributionSummary& d, int64_t period_ns) {
  Json j = Json::object();
  j["p50"] = ratio(static_cast<double>(d.p50_ns), static_cast<double>(period_ns));
  j["p99"] = ratio(static_cast<double>(d.p99_ns), static_cast<double>(period_ns));
  j["max"] = ratio(static_cast<double>(d.max_ns), static_cast<double>(period_ns));
  return j;
}

std::vector<std::string> latency_cells(const DistributionSummary& d) {
  return {fmt("%.1f", d.p50_ns / 1e3), fmt("%.1f", d.p99_ns / 1e3), fmt("%.1f", d.p999_ns / 1e3),
          fmt("%.1f", d.max_ns / 1e3)};
}


std::vector<std::string> row_of(const std::string& condition, int run, const std::string& source,
                                const DistributionSummary& d, const Json& run_json) {
  std::vector<std::string> row = {condition, std::to_string(run), source};
  for (auto& cell : latency_cells(d)) row.push_back(cell);
  const Json* overruns = run_json.find("overruns");
  row.push_back(overruns ? fmt("%.0f", overruns->number()) : "");
  const Json* steal = run_json.find("cpu_steal_fraction");
  row.push_back(steal ? fmt("%.1f", 100.0 * steal->number()) : "");
  return row;
}

// Min, median and max of a few values (the repetitions of one figure).
Json spread_json(std::vector<double> v) {
  Json j = Json::object();
  if (v.empty()) return j;
  std::sort(v.begin(), v.end());
  j["min"] = v.front();
  j["median"] = v.size() % 2 == 1 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  j["max"] = v.back();
  return j;
}

std::string spread_cell(const Json& s) {
  if (s.find("median") == nullptr) return "-";
  return fmt("%.2f", s.find("median")->number()) + " (" + fmt("%.2f", s.find("min")->number()) + "-" +
         fmt("%.2f", s.find("max")->number()) + ")";
}

Json stages_json(const TickStageSummary& st) {
  Json max = Json::object(), slowest = Json::object();
  for (std::size_t i = 0; i < kTickStageCount; ++i) {
    const std::string name(to_string(static_cast<TickStage>(i)));
    max[name] = static_cast<double>(st.max_ns[i]) / 1e3;
    slowest[name] = static_cast<double>(st.slowest_tick_ns[i]) / 1e3;
  }
  Json j = Json::object();
  j["max_us"] = max;
  j["slowest_tick"] = st.slowest_tick;
  j["slowest_tick_us"] = slowest;
  return j;
}

// One repetition: the loop, then cyclictest, under the same condition.
struct Repetition {
  Json json = Json::object();
  TimingSummary loop;
  std::optional<DistributionSummary> kernel;
};

Repetition repetition(Context& ctx, const RealtimeConfig& rt, bool fifo, int64_t period_us, double seconds,
                      const std::string& tag) {
  Repetition r;
  const CpuTimes loop_before = read_cpu_times();
  r.loop = run_loop(ctx, seconds, tag).timing;
  Json l = Json::object();
  l["wakeup_latency"] = latency_json(r.loop.wakeup_latency);
  l["compute"] = latency_json(r.loop.compute);
  l["compute_fraction_of_period"] = fraction_json(r.loop.compute, period_us * 1000);
  l["stages"] = stages_json(r.loop.stages);
  l["ticks"] = r.loop.ticks;
  l["overruns"] = r.loop.overruns;
  l["missed_ticks"] = r.loop.missed_ticks;
  l["cpu_steal_fraction"] = steal_fraction(loop_before, read_cpu_times());
  l["load_average_1min_after"] = load_average_1min();
  r.json["rigctl"] = l;
  if (ctx.stop.load()) return r;
  const CpuTimes ct_before = read_cpu_times();
  const int64_t loops = std::llround(seconds * 1e6 / static_cast<double>(period_us));
  CyclictestRun ct = run_cyclictest(ctx, rt, fifo, period_us, loops, tag);
  ct.json["cpu_steal_fraction"] = steal_fraction(ct_before, read_cpu_times());
  r.json["cyclictest"] = ct.json;
  r.kernel = ct.latency;
  if (!ct.latency) {
    const Json* why = ct.json.find("reason");
    if (why == nullptr) why = ct.json.find("error");
    ctx.out << "  cyclictest (" << tag << "): " << (why ? why->string() : "no result") << "\n";
  }
  return r;
}

struct ConditionFigures {
  std::vector<double> p50, p99, p999, max;  // ratios rigctl / cyclictest
  std::vector<double> compute_max_us, overruns;
  TimingSummary worst;  // the repetition with the longest tick
};

void add(ConditionFigures& f, const Repetition& r) {
  const DistributionSummary& w = r.loop.wakeup_latency;
  if (r.kernel) {
    const DistributionSummary& k = *r.kernel;
    f.p50.push_back(ratio(w.p50_ns, k.p50_ns));
    f.p99.push_back(ratio(w.p99_ns, k.p99_ns));
    f.p999.push_back(ratio(w.p999_ns, k.p999_ns));
    f.max.push_back(ratio(w.max_ns, k.max_ns));
  }
  f.compute_max_us.push_back(static_cast<double>(r.loop.compute.max_ns) / 1e3);
  f.overruns.push_back(static_cast<double>(r.loop.overruns));
  if (f.compute_max_us.size() == 1 || r.loop.compute.max_ns > f.worst.compute.max_ns) f.worst = r.loop;
}

}  // namespace

Section timing_section() {
  return {"timing", "timing: loop wake-up latency vs cyclictest, compute per tick", [](Context& ctx) {
            const RigConfig config = load_rig_config(ctx.quarter_car_config);
            const RealtimeConfig& rt = config.loop.realtime;
            const int64_t period_ns = std::llround(config.loop.period_s * 1e9);
            const int64_t period_us = period_ns / 1000;
            const double seconds = ctx.pick(30.0, 2.0);
            const std::string refusal = rt.enabled ? realtime_refusal(rt.priority) : "real-time disabled in the config";
            const bool fifo = refusal.empty();
            const int load_threads = static_cast<int>(std::max<long>(1, sysconf(_SC_NPROCESSORS_ONLN)));

            Json j = Json::object();
            j["config"] = ctx.quarter_car_config;
            j["period_us"] = period_us;
            j["priority"] = rt.priority;
            j["cpu"] = rt.cpu;
            j["scheduling"] = fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : "best effort: " + refusal;
            j["seconds_per_run"] = seconds;
            ctx.out << "  " << seconds << " s each at " << period_us << " us, "
                    << (fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : "best effort (" + refusal + ")")
                    << (rt.hold_cpu_dma_latency ? ", cpu_dma_latency held at 0 (as configured)" : "") << "\n";

            const int repetitions = ctx.pick(3, 1);
            j["repetitions"] = repetitions;
            j["order"] = "per condition, interleaved: rigctl loop, cyclictest, rigctl loop, cyclictest, ...";
            Table latency({"condition", "run", "source", "p50 us", "p99 us", "p99.9 us", "max us", "overruns", "steal %"});
            Table ratios({"condition", "p50", "p99", "p99.9", "max", "tick compute max us", "overruns"});
            for (const std::string condition : {"idle", "load"}) {
              if (ctx.stop.load()) break;
              Json c = Json::object();
              std::optional<CpuLoad> load;
              if (condition == "load") {
                load.emplace(load_threads, repetitions * (4 * seconds + 30.0) + 30.0);
                c["load"] = std::to_string(load_threads) +
                            " busy threads (normal priority) streaming through 8 MB buffers each";
              }
              c["load_average_1min_before"] = load_average_1min();
              ConditionFigures f;
              Json runs = Json::array();
              for (int k = 0; k < repetitions && !ctx.stop.load(); ++k) {
                const std::string tag = condition + "-" + std::to_string(k + 1);
                Repetition r = repetition(ctx, rt, fifo, period_us, seconds, tag);
                add(f, r);
                runs.push_back(r.json);
                latency.row(row_of(condition, k + 1, "rigctl loop", r.loop.wakeup_latency, r.json["rigctl"]));
                if (r.kernel) latency.row(row_of(condition, k + 1, "cyclictest", *r.kernel, r.json["cyclictest"]));
              }
              if (load) load->stop();
              c["runs"] = runs;
              Json summary = Json::object();
              summary["p50"] = spread_json(f.p50);
              summary["p99"] = spread_json(f.p99);
              summary["p999"] = spread_json(f.p999);
              summary["max"] = spread_json(f.max);
              c["ratio_rigctl_over_cyclictest"] = summary;
              c["compute_max_us"] = spread_json(f.compute_max_us);
              c["overruns"] = spread_json(f.overruns);
              c["slowest_tick_of_all_runs"] = stages_json(f.worst.stages);
              c["load_average_1min_after"] = load_average_1min();
              ratios.row({condition, spread_cell(summary["p50"]), spread_cell(summary["p99"]), spread_cell(summary["p999"]),
                          spread_cell(summary["max"]), spread_cell(c["compute_max_us"]), spread_cell(c["overruns"])});
              ctx.out << "  " << condition << ": slowest tick " << f.worst.stages.slowest_tick << " of its run: "
                      << describe_stages(f.worst.stages.slowest_tick_ns) << "\n";
              j[condition] = c;
            }
            ctx.out << "  wake-up latency (time past the deadline; steal: CPU time the hypervisor took during the run):\n"
                    << latency.text("    ")
                    << "  rigctl over cyclictest, median (min-max) of " << repetitions << ", and the tick's compute:\n"
                    << ratios.text("    ");
            return j;
          }};
}

}  // namespace rigctl::bench
