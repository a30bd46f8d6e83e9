// A hidden-effect run for the diagnosis tests, made as a user makes it
// (`rigctl make-run ... --truth FILE`), and what the generator says it hid,
// read back from its truth file: the tests never recompute the truth, so it
// holds for the perturbed world the run was actually made in.
#pragma once

#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "process.hpp"

namespace rigctl::test {

struct HiddenRun {
  bool made = false;
  std::string output;                        // make-run's output (why it failed)
  std::string csv;                           // the run file
  std::map<std::string, double> truth;       // "cause.param" -> value; "drawn.name" -> the drawn factor
  std::map<std::string, std::string> forms;  // cause -> the physical form made
};

namespace detail {

// `"key": {"a": 1, "b": 2}` from `pos` on: each name and number, prefixed.
inline void read_numbers(const std::string& s, std::size_t open, const std::string& prefix,
                         std::map<std::string, double>& out) {
  const std::size_t close = s.find('}', open);
  std::size_t q = open;
  while ((q = s.find('"', q)) != std::string::npos && q < close) {
    const std::size_t q2 = s.find('"', q + 1);
    const std::size_t colon = s.find(':', q2);
    out[prefix + s.substr(q + 1, q2 - q - 1)] = std::stod(s.substr(colon + 1));
    q = s.find_first_of(",}", colon) + 1;
  }
}

inline std::string string_after(const std::string& s, const std::string& key, std::size_t from) {
  const std::size_t k = s.find("\"" + key + "\": \"", from);
  if (k == std::string::npos) return "";
  const std::size_t b = k + key.size() + 5;
  return s.substr(b, s.find('"', b) - b);
}

}  // namespace detail

// The truth file written by tools/hidden_effects/make_run.cpp (flat enough
// to read by hand: a "drawn" object, then one object per effect).
inline void read_truth(const std::string& path, HiddenRun& run) {
  std::ifstream f(path);
  const std::string s((std::istreambuf_iterator<char>(f)), {});
  if (const auto d = s.find("\"drawn\": {"); d != std::string::npos) detail::read_numbers(s, d + 9, "drawn.", run.truth);
  std::size_t pos = 0;
  while ((pos = s.find("{\"cause\": \"", pos)) != std::string::npos) {
    const std::string cause = detail::string_after(s, "cause", pos);
    run.forms[cause] = detail::string_after(s, "form", pos);
    const std::size_t t = s.find("\"truth\": {", pos);
    detail::read_numbers(s, t + 9, cause + ".", run.truth);
    pos = s.find('}', t);
  }
}

// effects: CAUSE:LEVEL as make-run takes them; form -1: make-run's default (seed % 2).
inline HiddenRun make_hidden_run(const std::string& binary, const std::string& rig, const std::string& config,
                                 const std::vector<std::string>& effects, int seed, int form,
                                 const std::string& csv) {
  HiddenRun run;
  run.csv = csv;
  const std::string truth = csv + ".truth.json";
  std::string cmd = binary + " make-run --rig " + rig + " --config " + config + " --out " + csv + " --truth " + truth +
                    " --seed " + std::to_string(seed);
  if (form >= 0) cmd += " --form " + std::to_string(form);
  for (const auto& e : effects) cmd += " --effect " + e;
  const auto r = run_command(cmd);
  run.made = r.exit_code == 0;
  run.output = r.output;
  if (run.made) read_truth(truth, run);
  return run;
}

}  // namespace rigctl::test
