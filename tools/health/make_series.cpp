#include "tools/health/make_series.hpp"

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/catalog/run_summary.hpp"
#include "tools/common/json_text.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/hidden_effects/perturbation.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl::health {

namespace {

namespace fs = std::filesystem;

// The block's drift: 0 at the first block, 1 at the last, linear in time.
double progress_of(int block, int blocks) { return blocks > 1 ? static_cast<double>(block) / (blocks - 1) : 0.0; }

// Puts `# start_utc:` at the top of a run file (the catalog's start of the block).
void stamp_start(const std::string& csv, const std::string& start_utc) {
  std::ifstream in(csv);
  std::stringstream body;
  body << in.rdbuf();
  in.close();
  const std::string tmp = csv + ".tmp";
  {
    std::ofstream out(tmp);
    out << "# start_utc: " << start_utc << "\n" << body.str();
    if (!out) throw std::runtime_error("make-series: cannot write '" + tmp + "'");
  }
  fs::rename(tmp, csv);
}

struct Block {
  std::string file, start_utc;
  double leakage_resistance = 0.0, rod_damping = 0.0;
};

// One block: the rig as drawn, drifted, its own sensor noise.
Block run_block(const SeriesOptions& o, const std::string& config_path, const std::string& case_name, int i,
                std::ostream& progress) {
  const RigEffectGenerator& gen = effect_generator(o.rig);
  RigConfig config = load_rig_config(config_path, case_name);
  config.driver = DriverKind::kSim;
  config.telemetry.lcm_url = "memq://";
  for (auto& [name, s] : config.sensors) {
    s.offset = 0.0;
    s.delay_s = 0.0;
  }
  gen.make_clean(config);
  std::ostringstream name;
  name << "block-" << std::setw(3) << std::setfill('0') << i;
  const std::string stem = (fs::path(o.out_dir) / name.str()).string();
  Perturbation draw(static_cast<uint64_t>(o.seed), o.tolerance);  // the same seed: the same rig every block
  gen.perturb(config, draw, stem + ".demand");
  config.seed = static_cast<uint64_t>(o.seed) * 1000u + static_cast<uint64_t>(i);  // the block's own noise
  const double f = progress_of(i, o.blocks);
  if (o.rig != RigKind::kQuarterCar && (o.leakage_growth != 0.0 || o.friction_growth != 0.0))
    throw std::invalid_argument("make-series: drifts are made for the quarter car only");
  auto& p = config.quarter_car;
  p.leakage_resistance /= 1.0 + o.leakage_growth * f;  // conductance 1/R_l grows linearly
  p.rod_damping *= 1.0 + o.friction_growth * f;
  Block b{stem + ".csv",
          catalog::utc_text(static_cast<int64_t>((catalog::utc_seconds(o.start_utc) + i * o.block_spacing_h * 3600.0) * 1e6)),
          p.leakage_resistance, p.rod_damping};
  RunOptions run;
  run.config_path = config_path;
  run.case_name = case_name;
  if (o.duration_s > 0.0) run.duration_s = o.duration_s;
  run.fast = true;
  run.realtime = false;
  run.csv_path = b.file;
  run.csv_truth_channels = false;
  run.log_path = stem + ".lcm";
  std::atomic<bool> stop{false};
  std::ostringstream quiet;  // the run's own report is not the series'
  const RunReport report = run_rig(config, run, stop, quiet);
  fs::remove(run.log_path);
  fs::remove(run.log_path + ".events");
  fs::remove(stem + ".demand.csv");
  if (report.loop.final_state != RigState::kStopped)
    throw std::runtime_error("make-series: block " + std::to_string(i) + " ended " + std::string(to_string(report.loop.final_state)));
  stamp_start(b.file, b.start_utc);
  progress << "make-series: " << b.file << " at " << b.start_utc << " (R_l " << b.leakage_resistance << ", Bvr "
           << b.rod_damping << ")\n";
  return b;
}

}  // namespace

void make_series(const SeriesOptions& o, std::ostream& progress) {
  if (o.blocks < 1) throw std::invalid_argument("make-series: --blocks must be at least 1");
  const RigEffectGenerator& gen = effect_generator(o.rig);
  const std::string config_path =
      o.config_path.empty() ? "config/" + std::string(to_string(o.rig)) + ".yaml" : o.config_path;
  const std::string case_name = o.case_name.empty() ? gen.excitation_case : o.case_name;
  fs::create_directories(o.out_dir);
  std::vector<Block> blocks;
  for (int i = 0; i < o.blocks; ++i) blocks.push_back(run_block(o, config_path, case_name, i, progress));
  std::ofstream f(fs::path(o.out_dir) / "series.json");
  f << "{\"rig\": " << json_string(std::string(to_string(o.rig))) << ", \"seed\": " << o.seed
    << ", \"leakage_growth\": " << json_number(o.leakage_growth) << ", \"friction_growth\": "
    << json_number(o.friction_growth) << ",\n \"blocks\": [";
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const auto& b = blocks[i];
    f << (i ? ",\n" : "\n") << "  {\"file\": " << json_string(fs::path(b.file).filename().string())
      << ", \"start_utc\": " << json_string(b.start_utc) << ", \"leakage_resistance\": " << json_number(b.leakage_resistance)
      << ", \"rod_damping\": " << json_number(b.rod_damping) << "}";
  }
  f << "\n]}\n";
  if (!f) throw std::runtime_error("make-series: cannot write series.json in '" + o.out_dir + "'");
}

}  // namespace rigctl::health
