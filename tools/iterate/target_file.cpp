#include "tools/iterate/target_file.hpp"

#include <cmath>
#include <filesystem>

#include "tools/iterate/rpc3_file.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

std::vector<double> resample(const std::vector<double>& x, double from_s, double to_s) {
  if (std::abs(from_s - to_s) <= 1e-9 * to_s || x.size() < 2) return x;
  const double span = static_cast<double>(x.size() - 1) * from_s;
  std::vector<double> out;
  for (double t = 0.0; t <= span + 1e-12; t += to_s) {
    const double pos = t / from_s;
    const auto i = std::min(static_cast<std::size_t>(pos), x.size() - 2);
    const double w = pos - static_cast<double>(i);
    out.push_back(x[i] * (1.0 - w) + x[i + 1] * w);
  }
  return out;
}

std::vector<double> read_target(const std::string& path, const std::string& channel, double period_s) {
  if (is_rpc3_path(path)) {
    const Rpc3File f = read_rpc3_file(path);
    return resample(f.channel(channel, path), f.period_s, period_s);
  }
  RunFileOptions columns;
  columns.required = {channel};
  const RunFile run = read_run_file(path, columns);
  return resample(run.col(channel), run.dt, period_s);
}

}  // namespace rigctl
