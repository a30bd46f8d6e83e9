#include "tools/identify/frf_file.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>

#include "tools/common/json_text.hpp"

namespace rigctl {

namespace {

std::string numbers(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + json_number(v[i]);
  return s + "]";
}

std::string channel(const FrfChannel& c) {
  return "{\"name\": " + json_string(c.name) + ", \"unit\": " + json_string(c.unit) + "}";
}

std::string curve(const FrfCurve& c) {
  std::vector<double> re, im;
  for (const auto& z : c.value) {
    re.push_back(z.real());
    im.push_back(z.imag());
  }
  std::string s = "{\"re\": " + numbers(re) + ", \"im\": " + numbers(im);
  if (!c.coherence.empty()) s += ", \"coherence\": " + numbers(c.coherence);
  return s + "}";
}

std::string curves(const std::vector<FrfCurve>& cs) {
  std::string s = "{";
  for (std::size_t i = 0; i < cs.size(); ++i) s += std::string(i ? ",\n    " : "\n    ") + json_string(cs[i].response) + ": " + curve(cs[i]);
  return s + "\n  }";
}

std::string series_map(const std::map<std::string, std::vector<double>>& m) {
  std::string s = "{";
  bool first = true;
  for (const auto& [k, v] : m) {
    s += std::string(first ? "\n    " : ",\n    ") + json_string(k) + ": " + numbers(v);
    first = false;
  }
  return s + "\n  }";
}

}  // namespace

std::string frf_to_json(const FrfData& f) {
  std::ostringstream o;
  const auto& e = f.excitation;
  const auto& m = f.estimation;
  o << "{\n  \"format\": \"rigctl-frf\",\n  \"version\": " << kFrfFormatVersion << ",\n"
    << "  \"rig\": " << json_string(f.rig) << ",\n  \"config\": " << json_string(f.config) << ",\n"
    << "  \"run_log\": " << json_string(f.run_log) << ",\n  \"sample_rate_hz\": " << json_number(f.sample_rate_hz) << ",\n"
    << "  \"channels\": {\"demand\": " << channel(f.demand) << ", \"command\": " << channel(f.command) << ", \"responses\": [";
  for (std::size_t i = 0; i < f.responses.size(); ++i) o << (i ? ", " : "") << channel(f.responses[i]);
  o << "]},\n  \"operating_point\": {\"demand\": " << json_number(f.operating_point.demand)
    << ", \"response_mean\": " << json_number(f.operating_point.response_mean)
    << ", \"command_mean\": " << json_number(f.operating_point.command_mean) << "},\n"
    << "  \"controller\": {\"type\": " << json_string(f.controller_type) << ", \"gains\": {";
  bool first = true;
  for (const auto& [k, v] : f.controller_gains) {
    o << (first ? "" : ", ") << json_string(k) << ": " << json_number(v);
    first = false;
  }
  o << "}},\n  \"excitation\": {\"kind\": " << json_string(e.kind) << ", \"band_hz\": [" << json_number(e.band_min_hz)
    << ", " << json_number(e.band_max_hz) << "], \"amplitude\": " << json_number(e.amplitude)
    << ", \"amplitude_requested\": " << json_number(e.amplitude_requested) << ", \"amplitude_clamp\": "
    << json_number(e.amplitude_clamp) << ", \"clamp_reason\": " << json_string(e.clamp_reason)
    << ", \"logged_peak\": " << json_number(e.logged_peak) << ", \"duration_s\": " << json_number(e.duration_s)
    << ", \"start_s\": " << json_number(e.start_s) << ", \"end_s\": " << json_number(e.end_s) << "},\n"
    << "  \"estimation\": {\"method\": " << json_string(m.method) << ", \"window\": " << json_string(m.window)
    << ", \"segment_s\": " << json_number(m.segment_s) << ", \"overlap\": " << json_number(m.overlap)
    << ", \"averages\": " << m.averages << ", \"analysed_s\": [" << json_number(m.analysed_from_s) << ", "
    << json_number(m.analysed_to_s) << "]},\n"
    << "  \"frequency_hz\": " << numbers(f.frequency_hz) << ",\n"
    << "  \"closed_loop\": " << curves(f.closed_loop) << ",\n"
    << "  \"plant\": " << curves(f.plant) << ",\n"
    << "  \"command_coherence\": " << numbers(f.command_coherence) << ",\n"
    << "  \"noise_floor\": " << series_map(f.noise_floor) << ",\n"
    << "  \"response_psd\": " << series_map(f.response_psd);
  if (!f.distortion.empty()) o << ",\n  \"distortion\": " << series_map(f.distortion);
  if (!f.model.empty()) o << ",\n  \"model\": " << curves(f.model);
  o << "\n}\n";
  return o.str();
}

void write_frf_file(const FrfData& frf, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << frf_to_json(frf);
  if (!out.flush()) throw std::runtime_error("failed writing " + path);
}

namespace {

// Reading: JSON is YAML's flow style, so yaml-cpp (already the config's
// parser) reads it; every key is looked up by its path for clear errors.
class Reader {
 public:
  Reader(const std::string& name) : name_(name) {}
  YAML::Node need(const YAML::Node& n, const std::string& key, const std::string& path) const {
    const YAML::Node v = n[key];
    if (!v) fail(path + key, "missing");
    return v;
  }
  [[noreturn]] void fail(const std::string& key, const std::string& why) const {
    throw FrfFileError(name_ + ": " + key + ": " + why);
  }
  template <typename T>
  T as(const YAML::Node& n, const std::string& key, const std::string& path) const {
    try {
      return need(n, key, path).as<T>();
    } catch (const YAML::Exception&) {
      fail(path + key, "wrong type");
    }
  }
  std::vector<double> series(const YAML::Node& n, const std::string& key, const std::string& path,
                             std::size_t size) const {
    const auto v = as<std::vector<double>>(n, key, path);
    if (size != 0 && v.size() != size) {
      fail(path + key, std::to_string(v.size()) + " values for " + std::to_string(size) + " frequencies");
    }
    return v;
  }
  FrfChannel channel(const YAML::Node& n, const std::string& path) const {
    return FrfChannel{as<std::string>(n, "name", path), as<std::string>(n, "unit", path)};
  }
  std::vector<FrfCurve> curves(const YAML::Node& root, const std::string& key, const std::vector<FrfChannel>& responses,
                               std::size_t size, bool with_coherence) const {
    const YAML::Node node = need(root, key, "");
    std::vector<FrfCurve> out;
    for (const auto& r : responses) {
      const std::string path = key + "." + r.name + ".";
      const YAML::Node c = need(node, r.name, key + ".");
      FrfCurve curve;
      curve.response = r.name;
      const auto re = series(c, "re", path, size), im = series(c, "im", path, size);
      for (std::size_t i = 0; i < size; ++i) curve.value.emplace_back(re[i], im[i]);
      if (with_coherence) curve.coherence = series(c, "coherence", path, size);
      out.push_back(std::move(curve));
    }
    return out;
  }

 private:
  std::string name_;
};

void read_excitation(const Reader& r, const YAML::Node& e, ExcitationRecord& x) {
  const std::string p = "excitation.";
  x.kind = r.as<std::string>(e, "kind", p);
  const auto band = r.series(e, "band_hz", p, 2);
  x.band_min_hz = band[0];
  x.band_max_hz = band[1];
  x.amplitude = r.as<double>(e, "amplitude", p);
  x.amplitude_requested = r.as<double>(e, "amplitude_requested", p);
  x.amplitude_clamp = r.as<double>(e, "amplitude_clamp", p);
  x.clamp_reason = r.as<std::string>(e, "clamp_reason", p);
  x.logged_peak = r.as<double>(e, "logged_peak", p);
  x.duration_s = r.as<double>(e, "duration_s", p);
  x.start_s = r.as<double>(e, "start_s", p);
  x.end_s = r.as<double>(e, "end_s", p);
}

void read_estimation(const Reader& r, const YAML::Node& e, EstimationRecord& m) {
  const std::string p = "estimation.";
  m.method = r.as<std::string>(e, "method", p);
  m.window = r.as<std::string>(e, "window", p);
  m.segment_s = r.as<double>(e, "segment_s", p);
  m.overlap = r.as<double>(e, "overlap", p);
  m.averages = r.as<int>(e, "averages", p);
  const auto span = r.series(e, "analysed_s", p, 2);
  m.analysed_from_s = span[0];
  m.analysed_to_s = span[1];
}

}  // namespace

FrfData parse_frf_json(const std::string& text, const std::string& name) {
  const Reader r(name);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw FrfFileError(name + ": not JSON: " + e.what());
  }
  if (!root.IsMap()) throw FrfFileError(name + ": not an FRF file (a JSON object expected)");
  const auto format = r.as<std::string>(root, "format", "");
  if (format == "rigctl-frf-matrix") r.fail("format", "a matrix FRF file (several drives, rigctl-frf-matrix); this reads single-channel files (rigctl-frf)");
  if (format != "rigctl-frf") r.fail("format", "not rigctl-frf");
  if (r.as<int>(root, "version", "") != kFrfFormatVersion) r.fail("version", "this rigctl reads version " + std::to_string(kFrfFormatVersion));
  FrfData f;
  f.rig = r.as<std::string>(root, "rig", "");
  f.config = r.as<std::string>(root, "config", "");
  f.run_log = r.as<std::string>(root, "run_log", "");
  f.sample_rate_hz = r.as<double>(root, "sample_rate_hz", "");
  const YAML::Node ch = r.need(root, "channels", "");
  f.demand = r.channel(r.need(ch, "demand", "channels."), "channels.demand.");
  f.command = r.channel(r.need(ch, "command", "channels."), "channels.command.");
  const YAML::Node responses = r.need(ch, "responses", "channels.");
  for (std::size_t i = 0; i < responses.size(); ++i) f.responses.push_back(r.channel(responses[i], "channels.responses[" + std::to_string(i) + "]."));
  if (f.responses.empty()) r.fail("channels.responses", "empty");
  const YAML::Node op = r.need(root, "operating_point", "");
  f.operating_point = {r.as<double>(op, "demand", "operating_point."), r.as<double>(op, "response_mean", "operating_point."),
                       r.as<double>(op, "command_mean", "operating_point.")};
  const YAML::Node ctl = r.need(root, "controller", "");
  f.controller_type = r.as<std::string>(ctl, "type", "controller.");
  f.controller_gains = r.as<std::map<std::string, double>>(ctl, "gains", "controller.");
  read_excitation(r, r.need(root, "excitation", ""), f.excitation);
  read_estimation(r, r.need(root, "estimation", ""), f.estimation);
  f.frequency_hz = r.series(root, "frequency_hz", "", 0);
  const std::size_t n = f.frequency_hz.size();
  if (n == 0) r.fail("frequency_hz", "empty");
  for (std::size_t i = 1; i < n; ++i) {
    if (!(f.frequency_hz[i] > f.frequency_hz[i - 1])) r.fail("frequency_hz", "not increasing at index " + std::to_string(i));
  }
  f.closed_loop = r.curves(root, "closed_loop", f.responses, n, true);
  f.plant = r.curves(root, "plant", f.responses, n, true);
  f.command_coherence = r.series(root, "command_coherence", "", n);
  for (const auto& c : f.responses) f.noise_floor[c.name] = r.series(r.need(root, "noise_floor", ""), c.name, "noise_floor.", n);
  f.noise_floor[f.command.name] = r.series(r.need(root, "noise_floor", ""), f.command.name, "noise_floor.", n);
  for (const auto& c : f.responses) f.response_psd[c.name] = r.series(r.need(root, "response_psd", ""), c.name, "response_psd.", n);
  f.response_psd[f.command.name] = r.series(r.need(root, "response_psd", ""), f.command.name, "response_psd.", n);
  if (root["distortion"]) {
    for (const auto& c : f.responses) f.distortion[c.name] = r.series(root["distortion"], c.name, "distortion.", n);
  }
  if (root["model"]) f.model = r.curves(root, "model", f.responses, n, false);
  return f;
}

FrfData read_frf_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FrfFileError("cannot read FRF file " + path);
  std::stringstream text;
  text << in.rdbuf();
  return parse_frf_json(text.str(), path);
}

const FrfCurve& FrfData::plant_of(const std::string& response) const {
  for (const auto& c : plant) {
    if (c.response == response) return c;
  }
  throw FrfFileError("the FRF has no plant response '" + response + "'");
}

const FrfCurve* FrfData::model_of(const std::string& response) const {
  for (const auto& c : model) {
    if (c.response == response) return &c;
  }
  return nullptr;
}

}  // namespace rigctl
