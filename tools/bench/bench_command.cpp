#include "tools/bench/bench_command.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "tools/bench/sections.hpp"

namespace rigctl {

namespace bench {

Json skipped(const std::string& reason) {
  Json j = Json::object();
  j["status"] = "skipped";
  j["reason"] = reason;
  return j;
}

namespace {

std::vector<Section> all_sections() {
  return {timing_section(), plant_section(), io_section(), diagnosis_section(), diagnosis_sweep_section(),
          scaling_section(), channels_section(), foxglove_section(), foxglove_limits_section(), procedure_section()};
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void write_json(const std::string& path, const Json& j) {
  if (path.empty()) return;
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error("cannot write " + tmp);
    f << j.dump(2);
    if (!f) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

}  // namespace bench

std::vector<std::string> bench_section_names() {
  std::vector<std::string> names;
  for (const auto& s : bench::all_sections()) names.push_back(s.name);
  return names;
}

int run_bench(const BenchOptions& options, const std::atomic<bool>& stop, std::ostream& out) {
  using namespace bench;
  const auto sections = all_sections();
  for (const auto& want : options.sections) {
    bool known = false;
    for (const auto& s : sections) known = known || s.name == want;
    if (!known) {
      std::string list;
      for (const auto& s : sections) list += (list.empty() ? "" : ", ") + s.name;
      throw std::invalid_argument("unknown bench section '" + want + "' (sections: " + list + ")");
    }
  }
  const std::string qc = options.config_dir + "/quarter_car.yaml";
  const std::string pn = options.config_dir + "/pneumatic_rotary.yaml";
  for (const auto& p : {qc, pn}) {
    if (!std::filesystem::exists(p)) {
      throw std::invalid_argument("bench needs " + p + " (run from the repository root or give --config-dir)");
    }
  }

  ScratchDir scratch("run");
  Context ctx{options, stop, out, scratch, qc, pn};

  Json doc = Json::object();
  doc["rigctl_bench"] = 1;
  doc["command"] = options.command_line;
  doc["quick"] = options.quick;
  doc["date_utc"] = utc_now();
  doc["machine"] = machine_json();
  doc["sections"] = Json::object();

  const auto& machine = doc["machine"];
  out << "rigctl bench" << (options.quick ? " --quick (rough numbers: checks that everything runs)" : "") << "\n"
      << "  machine: " << machine.find("nproc")->number() << " CPUs, " << machine.find("cpu_model")->string()
      << ", kernel " << machine.find("kernel")->string() << ", load average "
      << fmt("%.2f", load_average_1min()) << " at start\n";
  out.flush();

  int exit_code = 0;
  const auto bench_start = std::chrono::steady_clock::now();
  for (const auto& s : sections) {
    if (!options.sections.empty() &&
        std::find(options.sections.begin(), options.sections.end(), s.name) == options.sections.end()) {
      continue;
    }
    if (stop.load()) {
      doc["sections"][s.name] = skipped("interrupted");
      continue;
    }
    out << "\n" << s.title << "\n";
    out.flush();
    const auto start = std::chrono::steady_clock::now();
    Json result;
    try {
      result = s.run(ctx);
    } catch (const std::exception& e) {
      result = Json::object();
      result["status"] = "error";
      result["error"] = std::string(e.what());
      out << "  error: " << e.what() << "\n";
      exit_code = 1;
    }
    if (!result.contains("status")) result["status"] = "ok";
    result["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result["load_average_1min_after"] = load_average_1min();
    doc["sections"][s.name] = result;
    write_json(options.json_path, doc);  // partial results survive an interrupted run
    out.flush();
  }
  doc["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - bench_start).count();
  write_json(options.json_path, doc);
  out << "\nbench finished in " << fmt("%.1f", doc["seconds"].number()) << " s";
  if (!options.json_path.empty()) out << "; results in " << options.json_path;
  out << "\n";
  return stop.load() ? 130 : exit_code;
}

}  // namespace rigctl
