#include "tools/hidden_effects/make_run.hpp"

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "rt/parse_number.hpp"
#include "tools/hidden_effects/perturbation.hpp"
#include "tools/hidden_effects/rigs.hpp"
#include "tools/common/json_text.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl {

double parse_effect_level(const std::string& text) {
  if (text == "strong") return 1.0;
  if (text == "weak") return weak_level();
  const auto v = parse_finite(text);
  if (!v || !(*v > 0.0)) throw std::invalid_argument("effect level '" + text + "': expected weak, strong or a positive number");
  return *v;
}

const RigEffectGenerator& effect_generator(RigKind rig) {
  switch (rig) {
    case RigKind::kQuarterCar: return quarter_car_effect_generator();
    case RigKind::kPneumaticRotary: return pneumatic_rotary_effect_generator();
    case RigKind::kHalfCar: return half_car_effect_generator();
    case RigKind::kTwoPoster: return two_poster_effect_generator();
  }
  throw std::logic_error("effect_generator: rig kind out of range");
}

const RigEffectGenerator& effect_generator(const std::string& rig) { return effect_generator(parse_kind<RigKind>(rig)); }

namespace {

void write_truth(const std::string& path, const MakeRunOptions& o, const std::vector<AppliedEffect>& applied,
                 const Perturbation& draw) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write the truth file '" + path + "'");
  f << "{\n  \"rig\": " << json_string(std::string(to_string(o.rig))) << ",\n  \"seed\": " << o.seed
    << ",\n  \"tolerance\": " << json_number(o.tolerance) << ",\n  \"drawn\": {";
  bool first_draw = true;
  for (const auto& [k, v] : draw.drawn()) {
    f << (first_draw ? "" : ", ") << json_string(k) << ": " << json_number(v);
    first_draw = false;
  }
  f << "},\n  \"effects\": [";
  for (std::size_t i = 0; i < applied.size(); ++i) {
    const auto& a = applied[i];
    f << (i ? ",\n" : "\n") << "    {\"cause\": " << json_string(a.cause) << ", \"level\": " << json_number(a.level)
      << ", \"form\": " << json_string(a.form) << ", \"description\": " << json_string(a.description)
      << ", \"truth\": {";
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

}  // namespace

std::vector<AppliedEffect> make_run(const MakeRunOptions& o, std::ostream& progress) {
  const RigEffectGenerator& gen = effect_generator(o.rig);
  if (o.out_csv.empty()) throw std::invalid_argument("make-run needs an output run file (--out)");
  // The shipped config of each rig kind; the two-poster's is named for the car on it.
  const std::string config_path = !o.config_path.empty()         ? o.config_path
                                  : o.rig == RigKind::kTwoPoster ? std::string("config/half_car_two_poster.yaml")
                                                                 : "config/" + std::string(to_string(o.rig)) + ".yaml";
  const std::string case_name = o.case_name.empty() ? gen.excitation_case : o.case_name;
  RigConfig config = load_rig_config(config_path, case_name);
  if (config.rig != o.rig) {
    throw std::invalid_argument("config '" + config_path + "' is a '" + std::string(to_string(config.rig)) +
                                "' rig, not '" + std::string(to_string(o.rig)) + "'");
  }
  config.driver = DriverKind::kSim;  // the generator never drives hardware
  config.seed = static_cast<uint64_t>(o.seed);
  config.telemetry.lcm_url = "memq://";
  // Sensor effects (offset, delay) are the same for every rig kind.
  for (auto& [name, s] : config.sensors) {
    s.offset = 0.0;
    s.delay_s = 0.0;
  }
  gen.make_clean(config);
  if (o.form >= kForms) throw std::invalid_argument("effect form " + std::to_string(o.form) + ": expected 0 or 1");
  const int form = o.form >= 0 ? o.form : o.seed % kForms;
  std::vector<AppliedEffect> applied;
  for (const auto& [cause, level] : o.effects) {
    if (cause == "none") continue;
    applied.push_back(gen.apply(config, cause, level, form));
  }
  if (!(o.tolerance >= 0.0 && o.tolerance < 0.5))
    throw std::invalid_argument("parameter tolerance must be in [0, 0.5)");
  Perturbation draw(static_cast<uint64_t>(o.seed), o.tolerance);
  const std::string scratch = o.out_csv + ".demand";
  gen.perturb(config, draw, scratch);

  RunOptions run;
  run.config_path = config_path;
  run.case_name = case_name;
  if (o.duration_s > 0.0) run.duration_s = o.duration_s;
  run.fast = true;
  run.realtime = false;
  run.csv_path = o.out_csv;
  run.csv_truth_channels = false;  // the sim_* truth channels would give the hidden effect away
  // The LCM log is only the path to the CSV: kept beside it, removed after.
  run.log_path = o.out_csv + ".lcm";
  std::atomic<bool> stop{false};
  const RunReport report = run_rig(config, run, stop, progress);
  std::filesystem::remove(run.log_path);
  std::filesystem::remove(run.log_path + ".events");  // the event log beside it (SAFETY.md)
  std::filesystem::remove(scratch + ".csv");             // a varied demand table, if the rig made one
  // Simulated time waits for the publisher instead of dropping
  // (rt/queue_full_policy.hpp): a gap here is a bug, never a run file.
  if (report.loop.dropped_records > 0) {
    throw std::runtime_error("the generated run lost " + std::to_string(report.loop.dropped_records) +
                             " telemetry records");
  }
  if (report.loop.final_state != RigState::kStopped) {
    throw std::runtime_error("the generated run ended " + std::string(to_string(report.loop.final_state)) +
                             " (a hidden effect too strong for the rig's limits?)");
  }
  if (!o.truth_json.empty()) write_truth(o.truth_json, o, applied, draw);
  return applied;
}

}  // namespace rigctl
