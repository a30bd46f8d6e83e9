// Section 4 of `rigctl bench`: time and peak memory of `rigctl diagnose` on
// a 20 s quarter-car run (made by `rigctl make-run` with body-bearing
// friction hidden, as seed 000's story) and on the real EMPS record. Each
// diagnosis runs as a child process so that wait4 reports its own peak RSS.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "tools/bench/sections.hpp"
#include "tools/diagnosis/sweep.hpp"
#include "tools/hidden_effects/make_run.hpp"

namespace rigctl::bench {

namespace {

std::string self_exe() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) throw std::runtime_error("cannot find the rigctl binary (/proc/self/exe)");
  return std::string(buf, static_cast<std::size_t>(n));
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// One diagnosis as a child; the part's JSON with time, memory and what it found.
Json diagnose_child(Context& ctx, const std::string& label, const std::string& rig, const std::string& data,
                    double record_s) {
  const std::string json_out = ctx.scratch.file(label + ".json");
  const std::string log = ctx.scratch.file(label + ".log");
  const ChildResult r = run_child({self_exe(), "diagnose", "--rig", rig, "--data", data, "--json", json_out, "--quiet"},
                                  log, ctx.pick(600.0, 300.0), ctx.stop);
  Json j = Json::object();
  if (!r.started || r.exit_code != 0) {
    j["status"] = "error";
    j["error"] = r.started ? "rigctl diagnose failed: " + slurp(log) : r.error;
    ctx.out << "  " << label << ": failed\n";
    return j;
  }
  const Json d = Json::parse(slurp(json_out));
  j["status"] = "ok";
  j["record_s"] = record_s;
  j["wall_s"] = r.wall_s;
  j["cpu_s"] = r.user_s + r.system_s;
  j["peak_rss_mb"] = static_cast<double>(r.peak_rss_kb) / 1024.0;
  const Json* cause = d.find("cause");
  j["cause"] = cause ? cause->string() : "";
  if (const Json* causes = d.find("causes"); causes && causes->is_array() && !causes->items().empty()) {
    const Json& top = causes->items().front();
    j["signal"] = top.find("signal") ? top.find("signal")->string() : "";
    j["baseline_fit_percent"] = top.find("baseline_fit_percent") ? top.find("baseline_fit_percent")->number() : 0.0;
    j["extended_fit_percent"] = top.find("extended_fit_percent") ? top.find("extended_fit_percent")->number() : 0.0;
  }
  ctx.out << "  " << std::left << std::setw(34) << label << std::right << std::fixed << std::setprecision(1)
          << std::setw(7) << record_s << " s record " << std::setw(7) << r.wall_s << " s wall " << std::setw(7)
          << r.user_s + r.system_s << " s CPU " << std::setw(7) << j["peak_rss_mb"].number() << " MB peak   cause "
          << j["cause"].string() << "\n";
  return j;
}

}  // namespace

Section diagnosis_section() {
  return {"diagnosis", "diagnosis: time and peak memory of rigctl diagnose", [](Context& ctx) {
            Json j = Json::object();
            j["status"] = "ok";
            // Quarter-car runs from the generator's diagnosis demand tables
            // (17.5 s; 19.9 s for lift-off), seed 000's bearing friction and
            // the tyre lift-off hidden in the closed loop.
            for (const auto& [effect, label] :
                 std::vector<std::pair<std::string, std::string>>{{"bearing_friction", "quarter_car (bearing friction)"},
                                                                  {"tyre_liftoff", "quarter_car (tyre lift-off)"}}) {
              const std::string csv = ctx.scratch.file(effect + ".csv");
              std::vector<std::string> argv{self_exe(), "make-run", "--rig", "quarter_car", "--config",
                                            ctx.quarter_car_config, "--effect", effect + ":strong", "--out", csv};
              if (ctx.quick()) {
                argv.push_back("--duration");
                argv.push_back("3");
              }
              const ChildResult made = run_child(argv, ctx.scratch.file("make-run.log"), 120.0, ctx.stop);
              if (!made.started || made.exit_code != 0) {
                j[effect] = skipped("rigctl make-run failed: " + slurp(ctx.scratch.file("make-run.log")));
                continue;
              }
              std::ifstream f(csv);
              std::size_t rows = 0;
              for (std::string line; std::getline(f, line);)
                if (!line.empty() && line[0] != '#') ++rows;
              const double record_s = rows > 1 ? static_cast<double>(rows - 2) * 0.0025 : 0.0;  // header, first row at t = 0
              j["quarter_car_" + effect] = diagnose_child(ctx, label, "quarter_car", csv, record_s);
              if (ctx.quick()) break;
            }
            // The real EMPS record, beside the configs in the source tree.
            const std::string emps = (
                (std::filesystem::path(ctx.options.config_dir).parent_path().empty()
                     ? std::filesystem::path("tests/data")
                     : std::filesystem::path(ctx.options.config_dir).parent_path() / "tests/data") /
                "emps_estimation.csv").string();
            if (ctx.quick()) {
              j["emps"] = skipped("--quick: the EMPS record takes about half a minute");
              ctx.out << "  emps: skipped (--quick)\n";
            } else if (!std::filesystem::exists(emps)) {
              j["emps"] = skipped("no " + emps);
              ctx.out << "  emps: skipped (no " << emps << ")\n";
            } else {
              j["emps"] = diagnose_child(ctx, "emps (real record)", "linear_axis", emps, 24.8);
            }
            return j;
          }};
}

}  // namespace rigctl::bench

namespace rigctl::bench {

Section diagnosis_sweep_section() {
  return {"diagnosis_sweep", "diagnosis sweep: hidden effects at weak and strong levels, confusion matrix",
          [](Context& ctx) {
            Json j = Json::object();
            j["status"] = "ok";
            // The two-effect runs (strong, both seeds); the quarter car last, it is the slowest.
            const std::map<std::string, std::vector<std::pair<std::string, std::string>>> pairs{
                {"pneumatic_rotary", {{"bladder_hysteresis", "valve_null_offset"}, {"coulomb_friction", "sensor_delay"}}},
                {"half_car", {{"actuator_lag", "damper_asymmetry"}, {"sensor_delay", "tyre_liftoff"}}},
                {"quarter_car", {{"bearing_friction", "actuator_seal_friction"}, {"sensor_delay", "damper_asymmetry"}}}};
            for (const std::string rig : {"pneumatic_rotary", "half_car", "quarter_car"}) {
              if (!ctx.options.sweep_rig.empty() && ctx.options.sweep_rig != rig) continue;
              SweepOptions o;
              o.rig = rig;
              o.pairs = pairs.at(rig);
              o.config_path = ctx.options.config_dir + "/" + rig + ".yaml";
              o.threads = ctx.options.sweep_jobs;
              if (ctx.quick()) {  // two runs: checks the path, not the accuracy
                o.causes = {"sensor_offset"};
                o.levels = {1.0};
                o.seeds = {11};
                o.pairs.clear();
                o.clean_runs = 1;
                o.duration_s = 6.0;
                if (rig != "quarter_car") continue;
              }
              Json part = Json::object();
              try {
                effect_generator(rig);
              } catch (const std::exception& e) {
                j[rig] = skipped(e.what());
                ctx.out << "  " << rig << ": skipped (" << e.what() << ")\n";
                continue;
              }
              ctx.out << "  " << rig << ":\n";
              const SweepResult r = run_sweep(o, ctx.stop, ctx.out);
              std::ostringstream md;
              write_confusion_markdown(r, md);
              ctx.out << md.str();
              part["status"] = "ok";
              part["correct"] = r.correct;
              part["total"] = r.total;
              part["accuracy"] = r.total ? static_cast<double>(r.correct) / r.total : 0.0;
              part["pairs_found"] = r.pairs_found;
              part["pairs_total"] = r.pairs_total;
              part["wall_s"] = r.wall_s;
              part["jobs"] = r.jobs;
              part["confusion_markdown"] = md.str();
              Json cells = Json::array();
              for (const auto& c : r.cells) {
                Json cell = Json::object();
                cell["truth"] = c.truth;
                cell["level"] = c.level;
                cell["named"] = c.named;
                cell["seconds"] = c.seconds;
                cell["diagnose_seconds"] = c.diagnose_seconds;
                cell["gain_percent_points"] = c.gain;
                Json named = Json::array();
                for (const auto& x : c.all_named) named.push_back(x);
                cell["all_named"] = named;
                cell["unexplained"] = c.unexplained;
                cells.push_back(cell);
              }
              part["runs"] = cells;
              j[rig] = part;
            }
            return j;
          }};
}

}  // namespace rigctl::bench
