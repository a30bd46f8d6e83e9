#include "tools/runfile/run_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

namespace rigctl {

namespace {

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && (s[a] == ' ' || s[a] == '\t' || s[a] == '\r')) ++a;
  while (b > a && (s[b - 1] == ' ' || s[b - 1] == '\t' || s[b - 1] == '\r')) --b;
  return s.substr(a, b - a);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

// Empty optional with the reason when the cell is not a finite number.
std::optional<double> parse_number(const std::string& cell, std::string& why) {
  if (cell.empty()) {
    why = "empty cell";
    return std::nullopt;
  }
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (end == cell.c_str() || *end != '\0') {
    why = "not a number: '" + cell + "'";
    return std::nullopt;
  }
  if (!std::isfinite(v)) {
    why = "not a finite number: '" + cell + "'";
    return std::nullopt;
  }
  if (errno == ERANGE && std::abs(v) > 1.0) {
    why = "number out of range: '" + cell + "'";
    return std::nullopt;
  }
  return v;
}

}  // namespace

const std::vector<double>& RunFile::col(const std::string& name) const {
  auto it = columns.find(name);
  if (it == columns.end()) throw RunFileError("run file has no column '" + name + "'");
  return it->second;
}

std::optional<std::string> RunFile::meta(const std::string& key) const {
  for (const auto& [k, v] : metadata)
    if (k == key) return v;
  return std::nullopt;
}

std::optional<double> RunFile::meta_number(const std::string& key) const {
  const auto v = meta(key);
  if (!v) return std::nullopt;
  std::string why;
  const auto x = parse_number(trim(*v), why);
  if (!x) throw RunFileError("metadata '" + key + "': " + why);
  return x;
}

RunFileRig run_file_rig_from_string(const std::string& name) {
  if (const auto rig = kind_from_string<RunFileRig>(name)) return *rig;
  throw RunFileError(unknown_kind_message<RunFileRig>(name));
}

RunFileOptions run_file_columns(RunFileRig rig) {
  RunFileOptions o;
  switch (rig) {
    case RunFileRig::kQuarterCar:
      o.required = {"x_ref", "u", "x_r", "x_w", "x_b"};
      o.optional = {"v_w", "v_b", "p1", "p2", "f_t"};
      break;
    case RunFileRig::kPneumaticRotary:
      o.required = {"theta_d", "u", "theta", "dp"};
      o.optional = {"omega"};
      break;
    case RunFileRig::kHalfCar:
      o.required = {"z_r1", "z_r2", "z_s", "phi", "z_u1", "z_u2"};
      o.optional = {"f_1", "f_2"};
      break;
    case RunFileRig::kLinearAxis:
      o.required = {"u", "x"};
      o.optional = {"x_ref", "f_ext"};
      break;
    case RunFileRig::kDamper:
      o.required = {"x", "f"};
      o.optional = {"v", "u"};
      break;
  }
  return o;
}

namespace {

// The columns the parser keeps, as (index in the row, name), t first.
using CheckedColumns = std::vector<std::pair<std::size_t, std::string>>;

RunFileError failure(const std::string& name, const std::string& what) { return RunFileError(name + ": " + what); }

// A line before the header: blank or a `# key: value` metadata line (kept);
// false for the header itself.
bool read_preamble_line(const std::string& line, RunFile& rf) {
  const std::string tl = trim(line);
  if (tl.empty()) return true;
  if (tl[0] != '#') return false;
  const std::string body = trim(tl.substr(1));
  const auto colon = body.find(':');
  if (colon != std::string::npos) rf.metadata.emplace_back(trim(body.substr(0, colon)), trim(body.substr(colon + 1)));
  return true;
}

// The header row into rf.header, checked: t first, no name empty or twice,
// every required column there. Returns the columns to keep.
CheckedColumns read_header(const std::string& line, std::size_t line_no, const RunFileOptions& options, RunFile& rf,
                           const std::string& name) {
  const std::string where = "line " + std::to_string(line_no) + ": ";
  rf.header = split(line);
  if (rf.header.empty() || rf.header[0] != "t")
    throw failure(name, where + "the first column must be 't' (found '" + (rf.header.empty() ? std::string() : rf.header[0]) + "')");
  std::set<std::string> seen;
  for (const auto& h : rf.header) {
    if (h.empty()) throw failure(name, where + "empty column name in the header");
    if (!seen.insert(h).second) throw failure(name, where + "duplicate column '" + h + "'");
  }
  for (const auto& r : options.required)
    if (!seen.count(r)) throw failure(name, "missing required column '" + r + "'");
  const bool keep_all = options.required.empty() && options.optional.empty();
  CheckedColumns checked;
  for (std::size_t i = 0; i < rf.header.size(); ++i) {
    const auto& h = rf.header[i];
    const bool known = i == 0 || keep_all ||
                       std::find(options.required.begin(), options.required.end(), h) != options.required.end() ||
                       std::find(options.optional.begin(), options.optional.end(), h) != options.optional.end();
    if (known) checked.emplace_back(i, h);
  }
  return checked;
}

// One data row's kept cells into `row`; returns why the row is bad, "" when it is good.
std::string read_row(const std::string& line, std::size_t line_no, const std::vector<std::string>& header,
                     const CheckedColumns& checked, std::vector<double>& row) {
  const auto cells = split(line);
  if (cells.size() < header.size()) {
    return "line " + std::to_string(line_no) + ": short row, " + std::to_string(cells.size()) + " cells for " +
           std::to_string(header.size()) + " columns (column '" + header[cells.size()] + "' missing)";
  }
  if (cells.size() > header.size()) {
    return "line " + std::to_string(line_no) + ": " + std::to_string(cells.size()) + " cells for " +
           std::to_string(header.size()) + " columns";
  }
  for (std::size_t k = 0; k < checked.size(); ++k) {
    std::string why;
    const auto v = parse_number(cells[checked[k].first], why);
    if (!v) {
      return "line " + std::to_string(line_no) + ", column '" + checked[k].second + "' (#" +
             std::to_string(checked[k].first + 1) + "): " + why;
    }
    row[k] = *v;
  }
  return "";
}

// Enough rows, and a time span a double holds.
void check_rows_and_span(const std::vector<double>& t, const RunFileOptions& options, const std::string& name) {
  const std::size_t n = t.size();
  if (n < std::max<std::size_t>(options.min_rows, 2))
    throw failure(name, "only " + std::to_string(n) + " data rows (at least " +
                            std::to_string(std::max<std::size_t>(options.min_rows, 2)) + " needed)");
  // Finite cells can still span more than a double holds (-1e308 .. 1e308):
  // the steps or the resampling grid would then be infinite.
  if (!std::isfinite(t.back() - t.front())) {
    std::ostringstream os;
    os << "time span from " << t.front() << " to " << t.back() << " s is too large for a double";
    throw failure(name, os.str());
  }
}

// The median time step; throws at a step that does not increase, a gap or
// irregular sampling. `jitter`: some step is off the median by over 1 %.
double median_step(const std::vector<double>& t, const std::vector<std::size_t>& row_line, const std::string& name,
                   bool& jitter) {
  const std::size_t n = t.size();
  std::vector<double> steps(n - 1);
  for (std::size_t i = 1; i < n; ++i) {
    steps[i - 1] = t[i] - t[i - 1];
    if (!(steps[i - 1] > 0.0))
      throw failure(name, "line " + std::to_string(row_line[i]) + ": time does not increase (t = " + std::to_string(t[i]) +
                              " after " + std::to_string(t[i - 1]) + ")");
  }
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double dt = sorted[sorted.size() / 2];
  jitter = false;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const double r = steps[i] / dt;
    if (r > 1.5 || r < 0.5) {
      std::ostringstream os;
      os << "line " << row_line[i + 1] << ": time step " << steps[i] << " s against the median " << dt
         << " s (" << (r > 1.5 ? "a gap: samples missing" : "irregular sampling")
         << "); split the run there or resample it";
      throw failure(name, os.str());
    }
    if (std::abs(r - 1.0) > 0.01) jitter = true;
  }
  return dt;
}

// Jittered time stamps: the columns linearly interpolated onto the grid of rf.dt.
void resample_onto_grid(RunFile& rf, const std::vector<double>& t, const std::vector<std::vector<double>>& values,
                        const CheckedColumns& checked) {
  const std::size_t n = t.size();
  const double dt = rf.dt;
  rf.resampled = true;
  const std::size_t m = static_cast<std::size_t>(std::floor((t.back() - t.front()) / dt + 1e-9)) + 1;
  rf.t.resize(m);
  for (std::size_t j = 0; j < m; ++j) rf.t[j] = t.front() + static_cast<double>(j) * dt;
  for (std::size_t k = 1; k < checked.size(); ++k) {
    std::vector<double> out(m);
    std::size_t i = 0;
    for (std::size_t j = 0; j < m; ++j) {
      const double tj = rf.t[j];
      while (i + 2 < n && t[i + 1] <= tj) ++i;
      const double a = std::clamp((tj - t[i]) / (t[i + 1] - t[i]), 0.0, 1.0);
      out[j] = values[k][i] + a * (values[k][i + 1] - values[k][i]);
    }
    rf.columns[checked[k].second] = std::move(out);
  }
}

}  // namespace

RunFile parse_run_file(std::istream& in, const std::string& name, const RunFileOptions& options) {
  RunFile rf;
  std::string line;
  std::size_t line_no = 0;
  bool have_header = false;
  CheckedColumns checked;
  std::vector<std::vector<double>> values;  // per checked column
  std::vector<std::size_t> row_line;        // file line of each kept row
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no == 1 && line.size() >= 3 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!have_header) {
      if (read_preamble_line(line, rf)) continue;
      checked = read_header(line, line_no, options, rf, name);
      values.assign(checked.size(), {});
      have_header = true;
      continue;
    }
    if (trim(line).empty()) continue;  // a trailing blank line
    std::vector<double> row(checked.size());
    const std::string error = read_row(line, line_no, rf.header, checked, row);
    if (!error.empty()) {
      if (!options.drop_bad_rows) throw failure(name, error);
      ++rf.dropped_rows;
      continue;
    }
    for (std::size_t k = 0; k < checked.size(); ++k) values[k].push_back(row[k]);
    row_line.push_back(line_no);
  }
  if (!have_header) throw failure(name, "no header row (empty file or only metadata lines)");
  const auto& t = values[0];
  check_rows_and_span(t, options, name);
  bool jitter = false;
  rf.dt = median_step(t, row_line, name, jitter);
  if (jitter) {
    resample_onto_grid(rf, t, values, checked);
    return rf;
  }
  rf.t = t;
  for (std::size_t k = 1; k < checked.size(); ++k) rf.columns[checked[k].second] = std::move(values[k]);
  return rf;
}

RunFile read_run_file(const std::string& path, const RunFileOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunFileError(path + ": cannot open: " + std::strerror(errno));
  return parse_run_file(in, path, options);
}

}  // namespace rigctl
