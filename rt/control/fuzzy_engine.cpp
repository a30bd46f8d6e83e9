#include "rt/control/fuzzy_engine.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace rigctl {

double MembershipFunction::operator()(double x) const noexcept {
  if (x < a || x > d) return 0.0;
  if (x < b) return (x - a) / (b - a);  // a < b here
  if (x <= c) return 1.0;
  return (d - x) / (d - c);  // c < x <= d, so d > c
}

MembershipFunction MembershipFunction::from_spec(const MembershipFunctionSpec& spec) {
  const auto& p = spec.points;
  MembershipFunction f;
  if (spec.shape == MembershipShape::kTriangle) {
    if (p.size() != 3) throw std::invalid_argument("set " + spec.name + ": a triangle needs 3 points");
    f = {p[0], p[1], p[1], p[2]};
  } else {
    if (p.size() != 4) throw std::invalid_argument("set " + spec.name + ": a trapezoid needs 4 points");
    f = {p[0], p[1], p[2], p[3]};
  }
  for (double v : p) {
    if (!std::isfinite(v)) throw std::invalid_argument("set " + spec.name + ": points must be finite");
  }
  if (!(f.a <= f.b && f.b <= f.c && f.c <= f.d)) {
    throw std::invalid_argument("set " + spec.name + ": points must be non-decreasing");
  }
  return f;
}

namespace {

int find_set(const LinguisticVariableSpec& v, const std::string& name) {
  for (std::size_t i = 0; i < v.sets.size(); ++i) {
    if (v.sets[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void check_variable(const LinguisticVariableSpec& v, const char* role) {
  const std::string what = std::string(role) + " " + v.name;
  if (!(v.max > v.min) || !std::isfinite(v.min) || !std::isfinite(v.max)) {
    throw std::invalid_argument(what + ": universe needs min < max");
  }
  if (!(v.scale != 0.0) || !std::isfinite(v.scale)) throw std::invalid_argument(what + ": scale must be finite, non-zero");
  if (v.sets.empty()) throw std::invalid_argument(what + ": no membership functions");
  for (std::size_t i = 0; i < v.sets.size(); ++i) {
    if (v.sets[i].name.empty()) throw std::invalid_argument(what + ": a set has no name");
    for (std::size_t j = 0; j < i; ++j) {
      if (v.sets[j].name == v.sets[i].name) throw std::invalid_argument(what + ": set " + v.sets[i].name + " twice");
    }
  }
}

}  // namespace

FuzzyEngine::FuzzyEngine(const FuzzyEngineSpec& spec) : spec_(spec) {
  if (spec.inputs.empty()) throw std::invalid_argument("fuzzy engine: no inputs");
  if (spec.rules.empty()) throw std::invalid_argument("fuzzy engine: no rules");
  if (spec.resolution < 3) throw std::invalid_argument("fuzzy engine: resolution must be at least 3");
  auto make = [](const LinguisticVariableSpec& v, const char* role) {
    check_variable(v, role);
    Variable out{v.min, v.max, v.scale, {}};
    for (const auto& s : v.sets) out.sets.push_back(MembershipFunction::from_spec(s));
    return out;
  };
  std::size_t offset = 0;
  for (const auto& v : spec.inputs) {
    inputs_.push_back(make(v, "input"));
    input_offset_.push_back(offset);
    offset += v.sets.size();
  }
  output_ = make(spec.output, "output");

  for (std::size_t r = 0; r < spec.rules.size(); ++r) {
    const auto& rs = spec.rules[r];
    const std::string what = "rule " + std::to_string(r + 1);
    if (rs.antecedents.size() != spec.inputs.size()) {
      throw std::invalid_argument(what + ": needs one antecedent per input");
    }
    if (!(rs.weight >= 0.0 && rs.weight <= 1.0)) throw std::invalid_argument(what + ": weight must be in [0, 1]");
    Rule rule{{}, 0, rs.weight};
    for (std::size_t i = 0; i < rs.antecedents.size(); ++i) {
      const std::string& name = rs.antecedents[i];
      if (name.empty() || name == "any") {
        rule.antecedent.push_back(-1);
        continue;
      }
      const int idx = find_set(spec.inputs[i], name);
      if (idx < 0) throw std::invalid_argument(what + ": input " + spec.inputs[i].name + " has no set " + name);
      rule.antecedent.push_back(idx);
    }
    const int out = find_set(spec.output, rs.consequent);
    if (out < 0) throw std::invalid_argument(what + ": output " + spec.output.name + " has no set " + rs.consequent);
    rule.consequent = static_cast<std::size_t>(out);
    rules_.push_back(std::move(rule));
  }

  universe_in_.assign(inputs_.size(), 0.0);
  input_mu_.assign(offset, 0.0);
  rule_strength_.assign(rules_.size(), 0.0);
  set_level_.assign(output_.sets.size(), 0.0);
  const auto n = static_cast<std::size_t>(spec.resolution);
  samples_.resize(n);
  weights_.assign(n, 1.0);
  weights_.front() = weights_.back() = 0.5;
  const double h = (output_.max - output_.min) / static_cast<double>(n - 1);
  for (std::size_t k = 0; k < n; ++k) samples_[k] = output_.min + h * static_cast<double>(k);
  samples_.back() = output_.max;
  output_mu_.resize(output_.sets.size() * n);
  for (std::size_t s = 0; s < output_.sets.size(); ++s) {
    for (std::size_t k = 0; k < n; ++k) output_mu_[s * n + k] = output_.sets[s](samples_[k]);
  }
  aggregated_.assign(n, 0.0);
}

double FuzzyEngine::evaluate(std::span<const double> inputs) noexcept {
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    const Variable& v = inputs_[i];
    double x = i < inputs.size() ? inputs[i] : 0.0;
    if (!std::isfinite(x)) x = 0.0;
    x = std::clamp(v.scale * x, v.min, v.max);
    universe_in_[i] = x;
    for (std::size_t s = 0; s < v.sets.size(); ++s) input_mu_[input_offset_[i] + s] = v.sets[s](x);
  }
  std::fill(set_level_.begin(), set_level_.end(), 0.0);
  for (std::size_t r = 0; r < rules_.size(); ++r) {
    const Rule& rule = rules_[r];
    double strength = 1.0;
    for (std::size_t i = 0; i < rule.antecedent.size(); ++i) {
      if (rule.antecedent[i] < 0) continue;
      strength = std::min(strength, input_mu_[input_offset_[i] + static_cast<std::size_t>(rule.antecedent[i])]);
    }
    strength *= rule.weight;
    rule_strength_[r] = strength;
    set_level_[rule.consequent] = std::max(set_level_[rule.consequent], strength);
  }
  const std::size_t n = samples_.size();
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    double mu = 0.0;
    for (std::size_t s = 0; s < set_level_.size(); ++s) {
      if (set_level_[s] > 0.0) mu = std::max(mu, std::min(set_level_[s], output_mu_[s * n + k]));
    }
    aggregated_[k] = mu;
    num += weights_[k] * samples_[k] * mu;
    den += weights_[k] * mu;
  }
  crisp_ = den > 0.0 ? num / den : 0.5 * (output_.min + output_.max);
  return output_.scale * crisp_;
}

double FuzzyEngine::membership(std::size_t input, std::size_t set, double universe_value) const noexcept {
  return inputs_[input].sets[set](universe_value);
}

double FuzzyEngine::output_membership(std::size_t set, double universe_value) const noexcept {
  return output_.sets[set](universe_value);
}

int FuzzyEngine::input_set_index(std::size_t input, const std::string& name) const {
  return find_set(spec_.inputs.at(input), name);
}

int FuzzyEngine::output_set_index(const std::string& name) const { return find_set(spec_.output, name); }

FuzzyEngineSpec paper_fuzzy_spec(const PaperFuzzyScaling& scaling, PaperRuleTable table) {
  if (!(scaling.input1_range > 0.0) || !(scaling.input2_range > 0.0) || !(scaling.force_limit > 0.0)) {
    throw std::invalid_argument("paper fuzzy spec: ranges and force limit must be positive");
  }
  static constexpr std::array<const char*, 9> kNine = {"NVL", "NL", "NM", "NS", "ZE", "PS", "PM", "PL", "PVL"};
  auto nine_sets = [] {
    std::vector<MembershipFunctionSpec> sets;
    for (std::size_t k = 0; k < kNine.size(); ++k) {
      if (k == 0) {
        sets.push_back({kNine[k], MembershipShape::kTrapezoid, {-1.0, -1.0, -0.8, -0.6}});
      } else if (k == kNine.size() - 1) {
        sets.push_back({kNine[k], MembershipShape::kTrapezoid, {0.6, 0.8, 1.0, 1.0}});
      } else {
        // Peaks -0.6 .. 0.6 for NL .. PL; tenths written as j / 5 so that
        // each point is the correctly rounded decimal (ZE peaks at exactly 0).
        const double j = static_cast<double>(k) - 4.0;
        sets.push_back({kNine[k], MembershipShape::kTriangle, {(j - 1.0) / 5.0, j / 5.0, (j + 1.0) / 5.0}});
      }
    }
    return sets;
  };
  FuzzyEngineSpec spec;
  spec.inputs.push_back({"theta", -1.0, 1.0, 1.0 / scaling.input1_range, nine_sets()});
  spec.inputs.push_back({"theta_ddot",
                         -1.0,
                         1.0,
                         1.0 / scaling.input2_range,
                         {{"N", MembershipShape::kTrapezoid, {-1.0, -1.0, -0.5, 0.0}},
                          {"ZE", MembershipShape::kTriangle, {-0.5, 0.0, 0.5}},
                          {"P", MembershipShape::kTrapezoid, {0.0, 0.5, 1.0, 1.0}}}});
  spec.output = {"f", -1.0, 1.0, scaling.force_limit, nine_sets()};

  // The printed table, rows theta NVL..PVL, columns N, ZE, P.
  static constexpr std::array<std::array<const char*, 3>, 9> kPrinted = {{
      {"NVL", "NVL", "NL"},
      {"NVL", "NL", "NM"},  // printed "NNL" for (NL, N)
      {"NL", "NM", "NS"},
      {"NM", "NS", "NS"},
      {"ZE", "ZE", "ZE"},
      {"PM", "PS", "PS"},
      {"PL", "PM", "PS"},
      {"PVL", "PL", "PM"},
      {"PVL", "PVL", "PL"},
  }};
  static constexpr std::array<const char*, 3> kThree = {"N", "ZE", "P"};
  auto negate = [](const char* name) -> const char* {
    for (std::size_t k = 0; k < kNine.size(); ++k) {
      if (std::string(kNine[k]) == name) return kNine[kNine.size() - 1 - k];
    }
    return name;
  };
  // Numbered as the paper does, column by column: rule 1 is (NVL, N),
  // rule 15 is (PS, ZE).
  for (std::size_t col = 0; col < kThree.size(); ++col) {
    for (std::size_t row = 0; row < kNine.size(); ++row) {
      const char* out = kPrinted[row][col];
      if (table == PaperRuleTable::kOddSymmetric && row > 4) {
        out = negate(kPrinted[kNine.size() - 1 - row][kThree.size() - 1 - col]);
      }
      spec.rules.push_back({{kNine[row], kThree[col]}, out, 1.0});
    }
  }
  return spec;
}

}  // namespace rigctl
