#include "tools/tune/tuned_config.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/tune/loop_gains.hpp"

namespace rigctl {

namespace {

std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  std::string s = b;
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";  // stays a float in YAML's eyes
  return s;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

bool top_level(const std::string& line) {
  return !line.empty() && line[0] != ' ' && line[0] != '\t' && line[0] != '#';
}

// The controller section's value check: what a loader reads back, in the
// keys and units LoopGains writes them (one mapping of keys to fields).
void check_loaded(const std::string& text, const std::string& name, const std::map<std::string, double>& values) {
  const auto loaded = LoopGains::from_config(parse_rig_config(text, name)).config_values();
  for (const auto& [key, v] : values) {
    const auto it = loaded.find(key);
    const double got = it == loaded.end() ? NAN : it->second;
    if (!(std::abs(got - v) <= 1e-5 * std::max(1.0, std::abs(v)))) {
      throw std::runtime_error(name + ": controller." + key + " did not load back as " + number(v));
    }
  }
}

}  // namespace

std::string with_controller_values(const std::string& text, const std::map<std::string, double>& values,
                                   const std::string& name) {
  auto lines = lines_of(text);
  std::size_t begin = 0;
  while (begin < lines.size() && !std::regex_match(lines[begin], std::regex(R"(controller:\s*(#.*)?)"))) ++begin;
  if (begin == lines.size()) throw std::runtime_error(name + ": no top-level controller: section to tune");
  std::size_t end = begin + 1;
  while (end < lines.size() && !top_level(lines[end])) ++end;
  std::string indent = "  ";
  for (std::size_t i = begin + 1; i < end; ++i) {
    const auto first = lines[i].find_first_not_of(" \t");
    if (first != std::string::npos && lines[i][first] != '#') {
      indent = lines[i].substr(0, first);
      break;
    }
  }
  for (const auto& [key, v] : values) {
    // `  key: value   # comment`: only the value changes.
    const std::regex entry("^(" + indent + key + R"(:\s*)([^\s#]+)(.*)$)");
    bool found = false;
    for (std::size_t i = begin + 1; i < end && !found; ++i) {
      std::smatch m;
      if (std::regex_match(lines[i], m, entry)) {
        lines[i] = m[1].str() + number(v) + m[3].str();
        found = true;
      }
    }
    if (!found) {
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(begin + 1), indent + key + ": " + number(v) + "  # added by rigctl tune");
      ++end;
    }
  }
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  check_loaded(out, name, values);
  return out;
}

void write_tuned_config(const std::string& config_path, const std::string& out_path,
                        const std::map<std::string, double>& values) {
  std::ifstream in(config_path);
  if (!in) throw std::runtime_error("cannot read " + config_path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string tuned = with_controller_values(text.str(), values, out_path);
  std::ofstream out(out_path);
  if (!out) throw std::runtime_error("cannot write " + out_path);
  out << tuned;
  if (!out.flush()) throw std::runtime_error("failed writing " + out_path);
}

}  // namespace rigctl
