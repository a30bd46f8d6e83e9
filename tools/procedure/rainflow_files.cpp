#include "tools/procedure/rainflow_files.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <stdexcept>

#include "tools/runfile/log2csv.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The run file of a run's LCM log, in a private temporary folder removed
// after reading (log2csv writes whole files only).
RunFile run_file_of_log(const std::string& lcm_path, const std::string& prefix) {
  const auto dir = std::filesystem::temp_directory_path() / ("rigctl-rainflow-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string csv = (dir / "run.csv").string();
  try {
    log_to_csv(lcm_path, csv, prefix);
    RunFileOptions o;
    o.min_rows = 2;
    RunFile f = read_run_file(csv, o);
    std::filesystem::remove_all(dir);
    return f;
  } catch (...) {
    std::filesystem::remove_all(dir);
    throw;
  }
}

struct Largest final : CycleSink {
  std::vector<RainflowCycle> top;
  void on_cycle(const RainflowCycle& c) noexcept override {
    top.push_back(c);
    std::sort(top.begin(), top.end(), [](const auto& a, const auto& b) { return a.range() > b.range(); });
    if (top.size() > 10) top.pop_back();
  }
};

// Counts into both sinks.
struct Both final : CycleSink {
  CycleSink& a;
  CycleSink& b;
  Both(CycleSink& x, CycleSink& y) : a(x), b(y) {}
  void on_cycle(const RainflowCycle& c) noexcept override {
    a.on_cycle(c);
    b.on_cycle(c);
  }
};

}  // namespace

void write_rainflow_matrix(const std::string& path, const std::string& channel, const RainflowMatrix& m) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error("rainflow: cannot write '" + tmp + "'");
    f << std::setprecision(10) << "# channel: " << channel << "\n# cycles: " << m.total_cycles()
      << "\n# pseudo_damage: " << m.damage() << "\n# basquin_exponent: " << m.basquin_exponent()
      << "\n# reference_range: " << m.reference_range() << "\n# bins: " << RainflowMatrix::kBins
      << " ranges from 0 and means from " << m.lo() << " to " << m.hi() << "\nrange,mean,cycles\n";
    for (std::size_t i = 0; i < RainflowMatrix::kBins; ++i) {
      for (std::size_t j = 0; j < RainflowMatrix::kBins; ++j) {
        if (m.count(i, j) > 0.0) f << m.range_bin_centre(i) << "," << m.mean_bin_centre(j) << "," << m.count(i, j) << "\n";
      }
    }
    if (!f.flush()) throw std::runtime_error("rainflow: writing '" + tmp + "' failed");
  }
  std::filesystem::rename(tmp, path);
}

std::vector<double> read_channel(const std::string& run_path, const std::string& channel, const std::string& prefix) {
  RunFileOptions o;
  o.min_rows = 2;
  const RunFile f = ends_with(run_path, ".lcm") ? run_file_of_log(run_path, prefix) : read_run_file(run_path, o);
  if (!f.has(channel)) {
    std::string known;
    for (const auto& h : f.header) known += (known.empty() ? "" : ", ") + h;
    throw std::runtime_error("rainflow: '" + run_path + "' has no channel '" + channel + "' (columns: " + known + ")");
  }
  return f.col(channel);
}

RainflowFileResult count_rainflow(const RainflowFileOptions& options) {
  const std::vector<double> x = read_channel(options.run_path, options.channel, options.channel_prefix);
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  RainflowFileResult r;
  r.samples = x.size();
  const double span = *hi - *lo;
  r.matrix.configure(*lo, *hi, options.basquin_exponent, options.reference_range > 0.0 ? options.reference_range : span);
  RainflowCounter counter;
  Largest largest;
  Both sink(r.matrix, largest);
  for (double v : x) counter.push(v, sink);
  counter.residue_half_cycles(sink);
  r.largest = largest.top;
  return r;
}

int run_rainflow_command(const RainflowFileOptions& options, std::ostream& out) {
  const RainflowFileResult r = count_rainflow(options);
  const RainflowMatrix& m = r.matrix;
  out << std::setprecision(6) << "rainflow (ASTM E1049 three-point) of " << options.channel << " in " << options.run_path
      << ": " << r.samples << " samples, " << m.total_cycles() << " cycles\n"
      << "  pseudo-damage " << m.damage() << " (Basquin exponent " << m.basquin_exponent() << ", reference range "
      << m.reference_range() << ")\n  largest ranges:";
  for (const auto& c : r.largest) out << " " << c.range() << (c.count < 1.0 ? " (half)" : "");
  out << "\n";
  if (!options.matrix_path.empty()) {
    write_rainflow_matrix(options.matrix_path, options.channel, m);
    out << "  matrix: " << options.matrix_path << "\n";
  }
  return 0;
}

}  // namespace rigctl
