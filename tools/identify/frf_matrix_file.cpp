#include "tools/identify/frf_matrix_file.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>

#include "tools/common/json_text.hpp"
#include "tools/identify/frf_file.hpp"

namespace rigctl {

namespace {

using Eigen::Index;

template <typename F>
std::string numbers(std::size_t n, F value) {
  std::string s = "[";
  for (std::size_t i = 0; i < n; ++i) s += (i ? ", " : "") + json_number(value(i));
  return s + "]";
}

std::string names_of(const std::vector<FrfChannel>& cs) {
  std::string s;
  for (const auto& c : cs) s += (s.empty() ? "" : ", ") + c.name;
  return s;
}

}  // namespace

std::string frf_matrix_to_json(const FrfMatrixData& m) {
  const MimoFrf& f = m.frf;
  const std::size_t n = f.frequency_hz.size();
  const auto& e = m.excitation;
  std::ostringstream o;
  o << "{\n  \"format\": " << json_string(kFrfMatrixFormat) << ",\n  \"version\": " << kFrfMatrixVersion << ",\n"
    << "  \"rig\": " << json_string(m.rig) << ",\n  \"config\": " << json_string(m.config) << ",\n"
    << "  \"run_log\": " << json_string(m.run_log) << ",\n  \"sample_rate_hz\": " << json_number(m.sample_rate_hz)
    << ",\n  \"drives\": [";
  for (std::size_t i = 0; i < m.drives.size(); ++i) {
    o << (i ? ", " : "") << "{\"name\": " << json_string(m.drives[i].name) << ", \"unit\": " << json_string(m.drives[i].unit)
      << ", \"operating_point\": " << json_number(m.operating_point[i]) << "}";
  }
  o << "],\n  \"responses\": [";
  for (std::size_t j = 0; j < m.responses.size(); ++j) {
    o << (j ? ",\n    " : "\n    ") << "{\"name\": " << json_string(m.responses[j].name)
      << ", \"unit\": " << json_string(m.responses[j].unit) << ", \"mean\": " << json_number(m.response_mean[j]) << "}";
  }
  o << "],\n  \"excitation\": {\"kind\": " << json_string(e.kind) << ", \"band_hz\": [" << json_number(e.band_min_hz)
    << ", " << json_number(e.band_max_hz) << "], \"amplitude\": " << numbers(e.amplitude.size(), [&](std::size_t i) { return e.amplitude[i]; })
    << ", \"realisations\": " << e.realisations << ", \"period_s\": " << json_number(e.period_s)
    << ", \"settle_periods\": " << e.settle_periods << ", \"seed\": " << e.seed << ", \"start_s\": " << json_number(e.start_s)
    << ", \"end_s\": " << json_number(e.end_s) << "},\n"
    << "  \"estimation\": {\"method\": \"h1\", \"window\": \"rectangular\", \"segment_s\": " << json_number(e.period_s)
    << ", \"averages\": " << f.averages << "},\n"
    << "  \"frequency_hz\": " << numbers(n, [&](std::size_t k) { return f.frequency_hz[k]; }) << ",\n"
    << "  \"input_condition\": " << numbers(n, [&](std::size_t k) { return f.input_condition[k]; }) << ",\n"
    << "  \"multiple_coherence\": {";
  for (std::size_t j = 0; j < m.responses.size(); ++j) {
    const auto jj = static_cast<Index>(j);
    o << (j ? ",\n    " : "\n    ") << json_string(m.responses[j].name) << ": "
      << numbers(n, [&](std::size_t k) { return f.multiple_coherence[k](jj); });
  }
  o << "\n  },\n  \"matrix\": [";
  bool first = true;
  for (std::size_t j = 0; j < m.responses.size(); ++j) {
    for (std::size_t i = 0; i < m.drives.size(); ++i) {
      const auto jj = static_cast<Index>(j), ii = static_cast<Index>(i);
      o << (first ? "\n    " : ",\n    ") << "{\"response\": " << json_string(m.responses[j].name)
        << ", \"drive\": " << json_string(m.drives[i].name)
        << ", \"re\": " << numbers(n, [&](std::size_t k) { return f.value[k](jj, ii).real(); })
        << ", \"im\": " << numbers(n, [&](std::size_t k) { return f.value[k](jj, ii).imag(); })
        << ", \"partial_coherence\": " << numbers(n, [&](std::size_t k) { return f.partial_coherence[k](jj, ii); }) << "}";
      first = false;
    }
  }
  o << "\n  ]\n}\n";
  return o.str();
}

void write_frf_matrix_file(const FrfMatrixData& m, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << frf_matrix_to_json(m);
  if (!out.flush()) throw std::runtime_error("failed writing " + path);
}

namespace {

class Reader {
 public:
  explicit Reader(const std::string& name) : name_(name) {}
  [[noreturn]] void fail(const std::string& key, const std::string& why) const { throw FrfFileError(name_ + ": " + key + ": " + why); }
  YAML::Node need(const YAML::Node& n, const std::string& key, const std::string& path) const {
    const YAML::Node v = n[key];
    if (!v) fail(path + key, "missing");
    return v;
  }
  template <typename T>
  T as(const YAML::Node& n, const std::string& key, const std::string& path) const {
    try {
      return need(n, key, path).as<T>();
    } catch (const YAML::Exception&) {
      fail(path + key, "wrong type");
    }
  }
  std::vector<double> series(const YAML::Node& n, const std::string& key, const std::string& path, std::size_t size) const {
    const auto v = as<std::vector<double>>(n, key, path);
    if (size != 0 && v.size() != size) fail(path + key, std::to_string(v.size()) + " values for " + std::to_string(size));
    return v;
  }

 private:
  std::string name_;
};

void read_excitation(const Reader& r, const YAML::Node& x, std::size_t drives, FrfMatrixExcitation& e) {
  const std::string p = "excitation.";
  e.kind = r.as<std::string>(x, "kind", p);
  const auto band = r.series(x, "band_hz", p, 2);
  e.band_min_hz = band[0];
  e.band_max_hz = band[1];
  e.amplitude = r.series(x, "amplitude", p, drives);
  e.realisations = r.as<std::size_t>(x, "realisations", p);
  e.period_s = r.as<double>(x, "period_s", p);
  e.settle_periods = r.as<std::size_t>(x, "settle_periods", p);
  e.seed = r.as<uint64_t>(x, "seed", p);
  e.start_s = r.as<double>(x, "start_s", p);
  e.end_s = r.as<double>(x, "end_s", p);
}

}  // namespace

FrfMatrixData parse_frf_matrix_json(const std::string& text, const std::string& name) {
  const Reader r(name);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FrfFileError(name + ": not JSON: " + e.what());
  }
  if (!root.IsMap()) throw FrfFileError(name + ": not an FRF file (a JSON object expected)");
  const auto format = r.as<std::string>(root, "format", "");
  if (format == "rigctl-frf") r.fail("format", "a single-channel FRF file (rigctl-frf); several drives need a matrix file (rigctl-frf-matrix) from rigctl identify on a rig with channels:");
  if (format != kFrfMatrixFormat) r.fail("format", "not " + std::string(kFrfMatrixFormat));
  if (r.as<int>(root, "version", "") != kFrfMatrixVersion) r.fail("version", "this rigctl reads version " + std::to_string(kFrfMatrixVersion));
  FrfMatrixData m;
  m.rig = r.as<std::string>(root, "rig", "");
  m.config = r.as<std::string>(root, "config", "");
  m.run_log = r.as<std::string>(root, "run_log", "");
  m.sample_rate_hz = r.as<double>(root, "sample_rate_hz", "");
  const YAML::Node drives = r.need(root, "drives", "");
  for (std::size_t i = 0; i < drives.size(); ++i) {
    const std::string p = "drives[" + std::to_string(i) + "].";
    m.drives.push_back({r.as<std::string>(drives[i], "name", p), r.as<std::string>(drives[i], "unit", p)});
    m.operating_point.push_back(r.as<double>(drives[i], "operating_point", p));
  }
  if (m.drives.empty()) r.fail("drives", "empty");
  const YAML::Node responses = r.need(root, "responses", "");
  for (std::size_t j = 0; j < responses.size(); ++j) {
    const std::string p = "responses[" + std::to_string(j) + "].";
    m.responses.push_back({r.as<std::string>(responses[j], "name", p), r.as<std::string>(responses[j], "unit", p)});
    m.response_mean.push_back(r.as<double>(responses[j], "mean", p));
  }
  if (m.responses.empty()) r.fail("responses", "empty");
  read_excitation(r, r.need(root, "excitation", ""), m.drives.size(), m.excitation);
  MimoFrf& f = m.frf;
  f.averages = r.as<int>(r.need(root, "estimation", ""), "averages", "estimation.");
  f.frequency_hz = r.series(root, "frequency_hz", "", 0);
  const std::size_t n = f.frequency_hz.size();
  if (n == 0) r.fail("frequency_hz", "empty");
  for (std::size_t k = 1; k < n; ++k) {
    if (!(f.frequency_hz[k] > f.frequency_hz[k - 1])) r.fail("frequency_hz", "not increasing at index " + std::to_string(k));
  }
  f.input_condition = r.series(root, "input_condition", "", n);
  const auto n_y = static_cast<Index>(m.responses.size()), n_x = static_cast<Index>(m.drives.size());
  f.value.assign(n, Eigen::MatrixXcd::Zero(n_y, n_x));
  f.multiple_coherence.assign(n, Eigen::VectorXd::Zero(n_y));
  f.partial_coherence.assign(n, Eigen::MatrixXd::Zero(n_y, n_x));
  const YAML::Node multiple = r.need(root, "multiple_coherence", "");
  for (Index j = 0; j < n_y; ++j) {
    const auto& c = m.responses[static_cast<std::size_t>(j)].name;
    const auto v = r.series(multiple, c, "multiple_coherence.", n);
    for (std::size_t k = 0; k < n; ++k) f.multiple_coherence[k](j) = v[k];
  }
  const YAML::Node matrix = r.need(root, "matrix", "");
  std::vector<bool> seen(static_cast<std::size_t>(n_y * n_x), false);
  for (std::size_t e = 0; e < matrix.size(); ++e) {
    const std::string p = "matrix[" + std::to_string(e) + "].";
    const auto resp = r.as<std::string>(matrix[e], "response", p), drive = r.as<std::string>(matrix[e], "drive", p);
    std::size_t j = 0, i = 0;
    try {
      j = m.response_index(resp);
      i = m.drive_index(drive);
    } catch (const std::invalid_argument& x) {
      r.fail(p + "response/drive", x.what());
    }
    const auto re = r.series(matrix[e], "re", p, n), im = r.series(matrix[e], "im", p, n);
    const auto pc = r.series(matrix[e], "partial_coherence", p, n);
    for (std::size_t k = 0; k < n; ++k) {
      f.value[k](static_cast<Index>(j), static_cast<Index>(i)) = {re[k], im[k]};
      f.partial_coherence[k](static_cast<Index>(j), static_cast<Index>(i)) = pc[k];
    }
    seen[j * static_cast<std::size_t>(n_x) + i] = true;
  }
  for (std::size_t j = 0; j < m.responses.size(); ++j) {
    for (std::size_t i = 0; i < m.drives.size(); ++i) {
      if (!seen[j * m.drives.size() + i]) r.fail("matrix", "no entry for " + m.responses[j].name + " from " + m.drives[i].name);
    }
  }
  return m;
}

FrfMatrixData read_frf_matrix_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FrfFileError("cannot read FRF file " + path);
  std::stringstream text;
  text << in.rdbuf();
  return parse_frf_matrix_json(text.str(), path);
}

std::string frf_file_format(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw FrfFileError(path + ": not JSON: " + e.what());
  }
  if (!root.IsMap() || !root["format"] || !root["format"].IsScalar()) throw FrfFileError(path + ": format: missing");
  const auto f = root["format"].as<std::string>();
  if (f != "rigctl-frf" && f != kFrfMatrixFormat) throw FrfFileError(path + ": format: " + f + " is not an FRF file's");
  return f;
}

std::size_t FrfMatrixData::drive_index(const std::string& name) const {
  for (std::size_t i = 0; i < drives.size(); ++i) {
    if (drives[i].name == name) return i;
  }
  throw std::invalid_argument("no drive '" + name + "' (drives: " + names_of(drives) + ")");
}

std::size_t FrfMatrixData::response_index(const std::string& name) const {
  for (std::size_t j = 0; j < responses.size(); ++j) {
    if (responses[j].name == name) return j;
  }
  throw std::invalid_argument("no response '" + name + "' in the FRF (responses: " + names_of(responses) + ")");
}

MimoFrf FrfMatrixData::rows(const std::vector<std::string>& names) const {
  std::vector<Index> pick;
  for (const auto& n : names) pick.push_back(static_cast<Index>(response_index(n)));
  MimoFrf out = frf;
  for (std::size_t k = 0; k < frf.value.size(); ++k) {
    out.value[k] = frf.value[k](pick, Eigen::all);
    out.partial_coherence[k] = frf.partial_coherence[k](pick, Eigen::all);
    out.multiple_coherence[k] = frf.multiple_coherence[k](pick);
  }
  return out;
}

}  // namespace rigctl
