// Strict access to a YAML config: every read names its key, every error names
// the file, line, key path and reason, and keys nobody read are reported as
// unknown. A rig must not start on a config it half understood.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "config/kind_names.hpp"

namespace rigctl {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ConfigReader {
 public:
  // Loads the file; throws ConfigError on I/O or YAML syntax errors. A
  // top-level `cases:` map holds named variants; case_name picks one and
  // merges it over the rest (mappings key by key, other values replaced).
  static ConfigReader load(const std::string& path, const std::string& case_name = "");
  static ConfigReader from_string(const std::string& text, const std::string& name,
                                  const std::string& case_name = "");
  // Names of the variants under `cases:` (empty when there are none).
  static std::vector<std::string> case_names(const std::string& path);

  bool has(const std::string& key) const;

  double number(const std::string& key, double min = -std::numeric_limits<double>::infinity(),
                double max = std::numeric_limits<double>::infinity());
  int64_t integer(const std::string& key, int64_t min, int64_t max);
  bool boolean(const std::string& key);
  std::string text(const std::string& key);
  std::string choice(const std::string& key, const std::vector<std::string>& allowed);
  // A kind (config/kind_names.hpp) by its name; an unknown name is an error
  // naming the kind and listing the known names.
  template <NamedKind Kind>
  Kind kind(const std::string& key) {
    const std::string name = text(key);
    if (const auto k = kind_from_string<Kind>(name)) return *k;
    fail(key, unknown_kind_message<Kind>(name));
  }
  std::vector<double> numbers(const std::string& key, std::size_t min_count, std::size_t max_count,
                              double min = -std::numeric_limits<double>::infinity(),
                              double max = std::numeric_limits<double>::infinity());
  // A list of strings; `check` may throw std::invalid_argument for an item,
  // which becomes an error naming KEY[i] and its line.
  std::vector<std::string> texts(const std::string& key,
                                 const std::function<void(const std::string&)>& check = {});
  ConfigReader child(const std::string& key);
  // A list of mappings (a procedure's `steps:`), each read as `KEY[i]`.
  std::vector<ConfigReader> items(const std::string& key);
  // Keys of a mapping child, in file order (for maps keyed by channel name).
  std::vector<std::string> keys() const;

  // Throws for any key of this mapping that was never read.
  void reject_unknown_keys() const;

  // An error about `key` of this node, with file, line and full key path.
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const;

  const std::string& file() const { return *file_; }
  std::string path_of(const std::string& key) const;

 private:
  ConfigReader(YAML::Node node, std::shared_ptr<const std::string> file, std::string path);
  static ConfigReader from_root(YAML::Node root, const std::string& name, const std::string& case_name);
  YAML::Node required(const std::string& key);
  [[noreturn]] void fail_at(const YAML::Node& node, const std::string& key, const std::string& reason) const;

  YAML::Node node_;
  std::shared_ptr<const std::string> file_;
  std::string path_;  // dotted path of this node, "" for the root
  std::shared_ptr<std::set<std::string>> used_;
};

}  // namespace rigctl
