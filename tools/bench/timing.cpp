// Timing section: wake-up latency of the rigctl loop (the simulated quarter
// car through `rigctl run`'s own code path, paced at the config's period and
// SCHED_FIFO priority) against cyclictest (Debian rt-tests) at the same
// interval and priority, one after the other; idle, then under a CPU load of
// one busy thread per CPU. Also the compute time of one tick (read to write)
// as a fraction of the period.
#include <sys/mman.h>

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
#include "tools/run/run_command.hpp"

namespace rigctl::bench {

LoopRun run_loop(Context& ctx, double seconds, const std::string& tag, const std::function<void(RunOptions&)>& adjust) {
  RunOptions o;
  o.config_path = ctx.quarter_car_config;
  o.duration_s = seconds;
  o.log_path = ctx.scratch.file("loop-" + tag + ".lcm");
  o.lcm_url = "memq://";
  if (adjust) adjust(o);
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
  return {report.loop.timing, report.wall_s, console.str()};
}

namespace {

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

}  // namespace

Section timing_section() {
  return {"timing", "timing: loop wake-up latency vs cyclictest, compute per tick", [](Context& ctx) {
            const RigConfig config = load_rig_config(ctx.quarter_car_config);
            const RealtimeConfig& rt = config.loop.realtime;
            const int64_t period_ns = std::llround(config.loop.period_s * 1e9);
            const int64_t period_us = period_ns / 1000;
            const double seconds = ctx.pick(30.0, 2.0);
            const int64_t loops = std::llround(seconds / config.loop.period_s);
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
            j["order"] = "per condition: rigctl loop, then cyclictest";
            ctx.out << "  " << seconds << " s each at " << period_us << " us, "
                    << (fifo ? "SCHED_FIFO " + std::to_string(rt.priority) : "best effort (" + refusal + ")")
                    << (rt.hold_cpu_dma_latency ? ", cpu_dma_latency held at 0 (as configured)" : "") << "\n";

            Table latency({"condition", "source", "p50 us", "p99 us", "p99.9 us", "max us", "overruns", "steal %"});
            Table compute({"condition", "compute p50 us", "p99 us", "max us", "p50/period", "p99/period", "max/period"});
            for (const std::string condition : {"idle", "load"}) {
              if (ctx.stop.load()) break;
              Json c = Json::object();
              std::optional<CpuLoad> load;
              if (condition == "load") {
                load.emplace(load_threads, 4 * seconds + 60.0);
                c["load"] = std::to_string(load_threads) +
                            " busy threads (normal priority) streaming through 8 MB buffers each";
              }
              c["load_average_1min_before"] = load_average_1min();

              const CpuTimes loop_before = read_cpu_times();
              const LoopRun loop = run_loop(ctx, seconds, condition);
              const double loop_steal = steal_fraction(loop_before, read_cpu_times());
              const TimingSummary& t = loop.timing;
              Json l = Json::object();
              l["wakeup_latency"] = latency_json(t.wakeup_latency);
              l["compute"] = latency_json(t.compute);
              l["compute_fraction_of_period"] = fraction_json(t.compute, period_ns);
              l["ticks"] = t.ticks;
              l["overruns"] = t.overruns;
              l["missed_ticks"] = t.missed_ticks;
              l["cpu_steal_fraction"] = loop_steal;
              c["rigctl"] = l;
              std::vector<std::string> row = {condition, "rigctl loop"};
              for (auto& cell : latency_cells(t.wakeup_latency)) row.push_back(cell);
              row.push_back(std::to_string(t.overruns));
              row.push_back(fmt("%.1f", 100.0 * loop_steal));
              latency.row(row);
              compute.row({condition, fmt("%.1f", t.compute.p50_ns / 1e3), fmt("%.1f", t.compute.p99_ns / 1e3),
                           fmt("%.1f", t.compute.max_ns / 1e3),
                           fmt("%.2f%%", 100.0 * ratio(t.compute.p50_ns, period_ns)),
                           fmt("%.2f%%", 100.0 * ratio(t.compute.p99_ns, period_ns)),
                           fmt("%.2f%%", 100.0 * ratio(t.compute.max_ns, period_ns))});

              if (!ctx.stop.load()) {
                const CpuTimes ct_before = read_cpu_times();
                const CyclictestRun ct = run_cyclictest(ctx, rt, fifo, period_us, loops, condition);
                const double ct_steal = steal_fraction(ct_before, read_cpu_times());
                c["cyclictest"] = ct.json;
                c["cyclictest"]["cpu_steal_fraction"] = ct_steal;
                if (ct.latency) {
                  const DistributionSummary& k = *ct.latency;
                  std::vector<std::string> krow = {condition, "cyclictest"};
                  for (auto& cell : latency_cells(k)) krow.push_back(cell);
                  krow.push_back("");
                  krow.push_back(fmt("%.1f", 100.0 * ct_steal));
                  latency.row(krow);
                  Json r = Json::object();
                  r["p50"] = ratio(t.wakeup_latency.p50_ns, k.p50_ns);
                  r["p99"] = ratio(t.wakeup_latency.p99_ns, k.p99_ns);
                  r["p999"] = ratio(t.wakeup_latency.p999_ns, k.p999_ns);
                  r["max"] = ratio(t.wakeup_latency.max_ns, k.max_ns);
                  c["ratio_rigctl_over_cyclictest"] = r;
                  latency.row({condition, "ratio", fmt("%.2f", r["p50"].number()), fmt("%.2f", r["p99"].number()),
                               fmt("%.2f", r["p999"].number()), fmt("%.2f", r["max"].number())});
                } else {
                  const Json* why = ct.json.find("reason");
                  if (why == nullptr) why = ct.json.find("error");
                  ctx.out << "  cyclictest (" << condition << "): " << (why ? why->string() : "no result") << "\n";
                }
              }
              if (load) load->stop();
              c["load_average_1min_after"] = load_average_1min();
              j[condition] = c;
            }
            ctx.out << "  wake-up latency (time past the deadline; steal: CPU time the hypervisor took during the run):\n" << latency.text("    ")
                    << "  compute per tick (read to write; period " << period_us << " us):\n" << compute.text("    ");
            return j;
          }};
}

}  // namespace rigctl::bench
