#include "tools/procedure/procedure_loader.hpp"

#include <filesystem>

#include "config/config_reader.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

// The drive at the loop's period: linear between the file's samples, from
// its first time to its last.
std::vector<double> resample(const std::vector<double>& t, const std::vector<double>& x, double period_s) {
  std::vector<double> out;
  const double t0 = t.front(), length = t.back() - t.front();
  const auto n = static_cast<std::size_t>(std::floor(length / period_s)) + 1;
  out.reserve(n);
  std::size_t j = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double ti = t0 + static_cast<double>(i) * period_s;
    while (j + 2 < t.size() && t[j + 1] < ti) ++j;
    const double w = t[j + 1] > t[j] ? (ti - t[j]) / (t[j + 1] - t[j]) : 0.0;
    out.push_back(x[j] + (x[j + 1] - x[j]) * std::min(1.0, std::max(0.0, w)));
  }
  return out;
}

void read_drive(StepSpec& s, const std::string& procedure_path, double period_s) {
  auto file = std::filesystem::path(s.drive_path);
  if (file.is_relative()) file = std::filesystem::path(procedure_path).parent_path() / file;
  try {
    RunFileOptions o;
    o.min_rows = 2;
    const RunFile f = read_run_file(file.string(), o);
    std::string column = s.drive_column;
    if (column.empty()) {
      for (const auto& h : f.header) {
        if (h != "t") {
          column = h;
          break;
        }
      }
    }
    if (!f.has(column)) throw RunFileError("no column '" + column + "'");
    s.drive = resample(f.t, f.col(column), period_s);
  } catch (const std::exception& e) {
    throw ConfigError(procedure_path + ": " + s.name + ".drive: file '" + file.string() + "': " + e.what());
  }
}

}  // namespace

ProcedureSpec load_procedure_for_run(const std::string& path, const ProcedureContext& context) {
  ProcedureSpec spec = load_procedure(path, context);
  for (auto& s : spec.steps) {
    if (s.kind == StepKind::kDrive) read_drive(s, path, context.period_s);
  }
  return spec;
}

}  // namespace rigctl
