#include "tools/hidden_effects.hpp"

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "tools/hidden_effects_rigs.hpp"
#include "tools/json_text.hpp"
#include "tools/run_command.hpp"

namespace rigctl {

double parse_effect_level(const std::string& text) {
  if (text == "strong") return 1.0;
  if (text == "weak") return weak_level();
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument("effect level '" + text + "': expected weak, strong or a positive number");
  }
  return v;
}

const RigEffectGenerator& effect_generator(const std::string& rig) {
  if (rig == "quarter_car") return quarter_car_effect_generator();
  if (rig == "pneumatic_rotary") return pneumatic_rotary_effect_generator();
  if (rig == "half_car") return half_car_effect_generator();
  throw std::invalid_argument("no hidden-effect generator for rig kind '" + rig +
                              "' (quarter_car, pneumatic_rotary, half_car)");
}

namespace {

void write_truth(const std::string& path, const MakeRunOptions& o, const std::vector<AppliedEffect>& applied) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write the truth file '" + path + "'");
  f << "{\n  \"rig\": " << json_string(o.rig) << ",\n  \"seed\": " << o.seed << ",\n  \"effects\": [";
  for (std::size_t i = 0; i < applied.size(); ++i) {
    const auto& a = applied[i];
    f << (i ? ",\n" : "\n") << "    {\"cause\": " << json_string(a.cause) << ", \"level\": " << json_number(a.level)
      << ", \"description\": " << json_string(a.description) << ", \"truth\": {";
    bool first = true;
    for (const auto& [k, v] : a.truth) {
      f << (first ? "" : ", ") << json_string(k) << ": " << json_number(v);
      first = false;
    }
    f << "}}";
  }
  f << (applied.empty() ? "]\n}\n" : "\n  ]\n}\n");
  if (!f) throw std::runtime_error("writing the truth file '" + path + "' failed");
}

// The simulator's truth channels (sim_*) would give the hidden effect away:
// the run file keeps only what a rig's transducers measure.
void drop_truth_columns(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  in.close();
  std::vector<bool> keep;
  std::ofstream out(path, std::ios::trunc);
  for (const auto& line : lines) {
    if (line.rfind("#", 0) == 0) {
      out << line << "\n";
      continue;
    }
    std::vector<std::string> cells;
    std::size_t a = 0;
    for (std::size_t b; (b = line.find(',', a)) != std::string::npos; a = b + 1) cells.push_back(line.substr(a, b - a));
    cells.push_back(line.substr(a));
    if (keep.empty()) {
      for (const auto& c : cells) keep.push_back(c.rfind("sim_", 0) != 0);
    }
    bool first = true;
    for (std::size_t i = 0; i < cells.size() && i < keep.size(); ++i) {
      if (!keep[i]) continue;
      out << (first ? "" : ",") << cells[i];
      first = false;
    }
    out << "\n";
  }
  if (!out) throw std::runtime_error("rewriting the run file '" + path + "' failed");
}

}  // namespace

std::vector<AppliedEffect> make_run(const MakeRunOptions& o, std::ostream& progress) {
  const RigEffectGenerator& gen = effect_generator(o.rig);
  if (o.out_csv.empty()) throw std::invalid_argument("make-run needs an output run file (--out)");
  const std::string config_path = o.config_path.empty() ? "config/" + o.rig + ".yaml" : o.config_path;
  const std::string case_name = o.case_name.empty() ? gen.excitation_case : o.case_name;
  RigConfig config = load_rig_config(config_path, case_name);
  if (config.rig != o.rig) {
    throw std::invalid_argument("config '" + config_path + "' is a '" + config.rig + "' rig, not '" + o.rig + "'");
  }
  config.driver = "sim";  // the generator never drives hardware
  config.seed = static_cast<uint64_t>(o.seed);
  config.telemetry.lcm_url = "memq://";
  gen.make_clean(config);
  std::vector<AppliedEffect> applied;
  for (const auto& [cause, level] : o.effects) {
    if (cause == "none") continue;
    applied.push_back(gen.apply(config, cause, level));
  }

  RunOptions run;
  run.config_path = config_path;
  run.case_name = case_name;
  if (o.duration_s > 0.0) run.duration_s = o.duration_s;
  run.fast = true;
  run.realtime = false;
  run.csv_path = o.out_csv;
  // The LCM log is only the path to the CSV: kept beside it, removed after.
  run.log_path = o.out_csv + ".lcm";
  std::atomic<bool> stop{false};
  const RunReport report = run_rig(config, run, stop, progress);
  std::filesystem::remove(run.log_path);
  std::filesystem::remove(run.log_path + ".events");  // the event log beside it (SAFETY.md)
  drop_truth_columns(o.out_csv);
  if (report.loop.final_state != RigState::kStopped) {
    throw std::runtime_error("the generated run ended " + std::string(to_string(report.loop.final_state)) +
                             " (a hidden effect too strong for the rig's limits?)");
  }
  if (!o.truth_json.empty()) write_truth(o.truth_json, o, applied);
  return applied;
}

}  // namespace rigctl
