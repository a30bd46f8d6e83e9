#include "config/config_reader.hpp"

#include <cmath>
#include <sstream>

namespace rigctl {

namespace {
std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string range_text(double min, double max) {
  if (std::isinf(min)) return "<= " + format_number(max);
  if (std::isinf(max)) return ">= " + format_number(min);
  return "in [" + format_number(min) + ", " + format_number(max) + "]";
}

const char* kind_name(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map: return "a mapping";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Scalar: return "a scalar";
    case YAML::NodeType::Null: return "empty";
    default: return "undefined";
  }
}

// A mapping key as text. YAML allows a list or a mapping as a key
// (`? [a, b] : 1`); config keys are names, so that is a config error rather
// than yaml-cpp's BadConversion escaping (found by tests/fuzz/fuzz_config).
std::string key_text(const YAML::Node& key, const std::string& file, const std::string& path) {
  if (key.IsMap() || key.IsSequence()) {
    throw ConfigError(file + ":" + std::to_string(key.Mark().line + 1) + ": " + (path.empty() ? "" : path + ": ") +
                      "expected a key name, got " + kind_name(key));
  }
  return key.as<std::string>();
}
}  // namespace

ConfigReader::ConfigReader(YAML::Node node, std::shared_ptr<const std::string> file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)),
      used_(std::make_shared<std::set<std::string>>()) {}

namespace {
// A case that changes a section's `type` gives another kind of section: it
// replaces the section whole (a csv profile shares no keys with a
// ramp_steps one, and the strict reader would refuse the leftovers).
bool retyped(const YAML::Node& base, const YAML::Node& overlay) {
  const YAML::Node a = base["type"], b = overlay["type"];
  return a && b && a.IsScalar() && b.IsScalar() && a.Scalar() != b.Scalar();
}

void merge_into(YAML::Node target, const YAML::Node& overlay, const std::string& file) {
  for (const auto& kv : overlay) {
    const auto key = key_text(kv.first, file, "cases");
    YAML::Node existing = target[key];
    if (kv.second.IsMap() && existing.IsMap() && !retyped(existing, kv.second)) {
      merge_into(existing, kv.second, file);
    } else {
      target[key] = YAML::Clone(kv.second);
    }
  }
}

YAML::Node load_file(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path + ": cannot open config file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
}
}  // namespace

ConfigReader ConfigReader::from_root(YAML::Node root, const std::string& name, const std::string& case_name) {
  if (!root.IsMap()) throw ConfigError(name + ": config must be a mapping of keys to values");
  const YAML::Node cases = root["cases"];
  if (cases.IsDefined() && !cases.IsMap()) {
    throw ConfigError(name + ":" + std::to_string(cases.Mark().line + 1) + ": cases: expected a mapping of case names");
  }
  if (!case_name.empty()) {
    if (!cases.IsDefined() || !cases[case_name].IsDefined()) {
      std::string known;
      if (cases.IsDefined()) {
        for (const auto& kv : cases) known += (known.empty() ? "" : ", ") + key_text(kv.first, name, "cases");
      }
      throw ConfigError(name + ": cases: no case '" + case_name + "'" +
                        (known.empty() ? " (the file defines none)" : " (cases: " + known + ")"));
    }
    const YAML::Node chosen = YAML::Clone(cases[case_name]);
    if (!chosen.IsMap()) {
      throw ConfigError(name + ":" + std::to_string(chosen.Mark().line + 1) + ": cases." + case_name +
                        ": expected a mapping of keys to override");
    }
    root.remove("cases");
    merge_into(root, chosen, name);
  } else {
    root.remove("cases");
  }
  return ConfigReader(root, std::make_shared<const std::string>(name), "");
}

ConfigReader ConfigReader::load(const std::string& path, const std::string& case_name) {
  return from_root(load_file(path), path, case_name);
}

ConfigReader ConfigReader::from_string(const std::string& text, const std::string& name, const std::string& case_name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
  return from_root(root, name, case_name);
}

std::vector<std::string> ConfigReader::case_names(const std::string& path) {
  const YAML::Node root = load_file(path);
  std::vector<std::string> names;
  // IsDefined() first: on a const node, a missing key is an invalid node whose
  // IsMap() throws YAML::InvalidNode (found by tests/fuzz/fuzz_config).
  if (root.IsMap() && root["cases"].IsDefined() && root["cases"].IsMap()) {
    for (const auto& kv : root["cases"]) names.push_back(key_text(kv.first, path, "cases"));
  }
  return names;
}

std::string ConfigReader::path_of(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

void ConfigReader::fail_at(const YAML::Node& node, const std::string& key, const std::string& reason) const {
  std::string where = *file_;
  const YAML::Node& located = node.IsDefined() ? node : node_;
  if (located.Mark().line >= 0) where += ":" + std::to_string(located.Mark().line + 1);
  throw ConfigError(where + ": " + path_of(key) + ": " + reason);
}

void ConfigReader::fail(const std::string& key, const std::string& reason) const {
  fail_at(node_[key], key, reason);
}

bool ConfigReader::has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

YAML::Node ConfigReader::required(const std::string& key) {
  used_->insert(key);
  YAML::Node n = node_[key];
  if (!n.IsDefined()) fail_at(node_, key, "missing required key");
  return n;
}

double ConfigReader::number(const std::string& key, double min, double max) {
  YAML::Node n = required(key);
  double v = 0.0;
  if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) {
    fail_at(n, key, std::string("expected a number, got ") + (n.IsScalar() ? "'" + n.Scalar() + "'" : kind_name(n)));
  }
  if (!std::isfinite(v)) fail_at(n, key, "must be a finite number");
  if (v < min || v > max) fail_at(n, key, "must be " + range_text(min, max) + ", got " + format_number(v));
  return v;
}

int64_t ConfigReader::integer(const std::string& key, int64_t min, int64_t max) {
  YAML::Node n = required(key);
  int64_t v = 0;
  if (!n.IsScalar() || !YAML::convert<int64_t>::decode(n, v)) {
    fail_at(n, key, std::string("expected an integer, got ") + (n.IsScalar() ? "'" + n.Scalar() + "'" : kind_name(n)));
  }
  if (v < min || v > max) {
    fail_at(n, key, "must be " + range_text(static_cast<double>(min), static_cast<double>(max)) + ", got " +
                        std::to_string(v));
  }
  return v;
}

bool ConfigReader::boolean(const std::string& key) {
  YAML::Node n = required(key);
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) {
    fail_at(n, key, std::string("expected true or false, got ") + (n.IsScalar() ? "'" + n.Scalar() + "'" : kind_name(n)));
  }
  return v;
}

std::string ConfigReader::text(const std::string& key) {
  YAML::Node n = required(key);
  if (!n.IsScalar()) fail_at(n, key, std::string("expected text, got ") + kind_name(n));
  return n.Scalar();
}

std::string ConfigReader::choice(const std::string& key, const std::vector<std::string>& allowed) {
  const std::string v = text(key);
  for (const auto& a : allowed) {
    if (v == a) return v;
  }
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail_at(node_[key], key, "unknown value '" + v + "' (expected one of: " + list + ")");
}

std::vector<double> ConfigReader::numbers(const std::string& key, std::size_t min_count, std::size_t max_count,
                                          double min, double max) {
  YAML::Node n = required(key);
  if (!n.IsSequence()) fail_at(n, key, std::string("expected a list of numbers, got ") + kind_name(n));
  if (n.size() < min_count || n.size() > max_count) {
    fail_at(n, key, "expected " + (min_count == max_count ? std::to_string(min_count)
                                                          : std::to_string(min_count) + " to " + std::to_string(max_count)) +
                        " numbers, got " + std::to_string(n.size()));
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < n.size(); ++i) {
    double v = 0.0;
    const std::string item = key + "[" + std::to_string(i) + "]";
    if (!n[i].IsScalar() || !YAML::convert<double>::decode(n[i], v) || !std::isfinite(v)) {
      fail_at(n[i], item, "expected a finite number");
    }
    if (v < min || v > max) fail_at(n[i], item, "must be " + range_text(min, max) + ", got " + format_number(v));
    out.push_back(v);
  }
  return out;
}

std::vector<std::string> ConfigReader::texts(const std::string& key,
                                            const std::function<void(const std::string&)>& check) {
  YAML::Node n = required(key);
  if (!n.IsSequence()) fail_at(n, key, std::string("expected a list of strings, got ") + kind_name(n));
  std::vector<std::string> out;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item = key + "[" + std::to_string(i) + "]";
    if (!n[i].IsScalar()) fail_at(n[i], item, "expected a string");
    const std::string v = n[i].as<std::string>();
    if (check) {
      try {
        check(v);
      } catch (const std::invalid_argument& e) {
        fail_at(n[i], item, e.what());
      }
    }
    out.push_back(v);
  }
  return out;
}

ConfigReader ConfigReader::child(const std::string& key) {
  YAML::Node n = required(key);
  if (!n.IsMap()) fail_at(n, key, std::string("expected a mapping of keys, got ") + kind_name(n));
  return ConfigReader(n, file_, path_of(key));
}

std::vector<ConfigReader> ConfigReader::items(const std::string& key) {
  YAML::Node n = required(key);
  if (!n.IsSequence()) fail_at(n, key, std::string("expected a list, got ") + kind_name(n));
  std::vector<ConfigReader> out;
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string item = key + "[" + std::to_string(i) + "]";
    if (!n[i].IsMap()) fail_at(n[i], item, std::string("expected a mapping of keys, got ") + kind_name(n[i]));
    out.push_back(ConfigReader(n[i], file_, path_of(item)));
  }
  return out;
}

std::vector<std::string> ConfigReader::keys() const {
  std::vector<std::string> out;
  for (const auto& kv : node_) out.push_back(key_text(kv.first, *file_, path_));
  return out;
}

void ConfigReader::reject_unknown_keys() const {
  for (const auto& kv : node_) {
    const auto key = key_text(kv.first, *file_, path_);
    if (used_->count(key) == 0) {
      std::string known;
      for (const auto& k : *used_) known += (known.empty() ? "" : ", ") + k;
      fail_at(kv.first, key, "unknown key (known here: " + known + ")");
    }
  }
}

}  // namespace rigctl
