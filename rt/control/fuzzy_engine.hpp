// A general Mamdani fuzzy inference engine, built from plain data
// (FuzzyEngineSpec mirrors a config file) and run allocation free.
//
//  1. Input scaling: each input's universe value is scale * physical value,
//     clamped to the variable's [min, max] (so the outermost sets act as
//     shoulders for anything beyond the range).
//  2. Fuzzification: triangle (a, b, c) or trapezoid (a, b, c, d)
//     membership functions, 0 outside [a, d], linear on the flanks, 1 on
//     [b, c] (a triangle is a trapezoid with b = c). A vertical flank
//     (a = b or c = d) belongs to the set: mu(a) = 1 when a = b.
//  3. Rules: IF x1 is A AND x2 is B ... THEN y is C (weight w): firing
//     strength w * min over the antecedents (AND = min); an antecedent "" or
//     "any" is "don't care".
//  4. Implication min (each rule clips its consequent at its strength),
//     aggregation max over rules: mu_agg(y) = max_s min(level_s, mu_s(y))
//     where level_s is the largest strength of the rules concluding s.
//  5. Defuzzification by centroid (seed 001 eq. 13),
//     y* = integral y mu_agg(y) dy / integral mu_agg(y) dy, evaluated on
//     `resolution` evenly spaced samples of the output universe with the
//     trapezoidal rule (exact for piecewise-linear mu_agg between samples up
//     to O(h^2)). When no rule fires, y* is the middle of the universe.
//  6. Output scaling: physical output = output.scale * y*.
// The membership table of the output sets on the samples and every buffer
// are allocated in the constructor; evaluate() is noexcept and allocation
// free but not reentrant (it fills the engine's buffers: one engine per
// thread).
#pragma once

#include <span>
#include <string>
#include <vector>

namespace rigctl {

enum class MembershipShape { kTriangle, kTrapezoid };

struct MembershipFunctionSpec {
  std::string name;                 // e.g. "NVL"
  MembershipShape shape = MembershipShape::kTriangle;
  std::vector<double> points;       // triangle: a, b, c; trapezoid: a, b, c, d; non-decreasing
};

struct LinguisticVariableSpec {
  std::string name;
  double min = -1.0;  // universe of discourse
  double max = 1.0;
  // Input: universe value = scale * physical value. Output: physical
  // value = scale * universe value.
  double scale = 1.0;
  std::vector<MembershipFunctionSpec> sets;
};

struct FuzzyRuleSpec {
  std::vector<std::string> antecedents;  // one set name per input, in input order; "" or "any" = don't care
  std::string consequent;                // output set name
  double weight = 1.0;                   // in [0, 1]
};

struct FuzzyEngineSpec {
  std::vector<LinguisticVariableSpec> inputs;
  LinguisticVariableSpec output;
  std::vector<FuzzyRuleSpec> rules;
  int resolution = 1001;  // output universe samples for the centroid, >= 3
};

// Membership function in evaluated form: trapezoid a <= b <= c <= d.
struct MembershipFunction {
  double a = 0.0, b = 0.0, c = 0.0, d = 0.0;
  double operator()(double x) const noexcept;
  static MembershipFunction from_spec(const MembershipFunctionSpec& spec);  // throws std::invalid_argument
};

class FuzzyEngine {
 public:
  // Throws std::invalid_argument naming what is wrong (unknown set name,
  // unordered points, rule of the wrong length, empty universe, ...).
  explicit FuzzyEngine(const FuzzyEngineSpec& spec);

  // Physical inputs in spec order (missing ones read as 0) -> physical output.
  double evaluate(std::span<const double> inputs) noexcept;

  // After evaluate(): the details of the last inference.
  double last_output_universe() const noexcept { return crisp_; }  // y* before output scaling
  double input_universe(std::size_t input) const noexcept { return universe_in_[input]; }
  double input_membership(std::size_t input, std::size_t set) const noexcept {
    return input_mu_[input_offset_[input] + set];
  }
  double rule_strength(std::size_t rule) const noexcept { return rule_strength_[rule]; }
  double output_level(std::size_t set) const noexcept { return set_level_[set]; }
  std::span<const double> aggregated() const noexcept { return aggregated_; }
  std::span<const double> output_samples() const noexcept { return samples_; }

  // Membership of a universe value in a set (no scaling, no clamping).
  double membership(std::size_t input, std::size_t set, double universe_value) const noexcept;
  double output_membership(std::size_t set, double universe_value) const noexcept;

  std::size_t input_count() const noexcept { return inputs_.size(); }
  std::size_t set_count(std::size_t input) const noexcept { return inputs_[input].sets.size(); }
  std::size_t output_set_count() const noexcept { return output_.sets.size(); }
  std::size_t rule_count() const noexcept { return rules_.size(); }
  // Index of a set by name; -1 when absent.
  int input_set_index(std::size_t input, const std::string& name) const;
  int output_set_index(const std::string& name) const;
  // Output set index that rule r concludes.
  std::size_t rule_consequent(std::size_t rule) const noexcept { return rules_[rule].consequent; }
  const FuzzyEngineSpec& spec() const noexcept { return spec_; }

 private:
  struct Variable {
    double min, max, scale;
    std::vector<MembershipFunction> sets;
  };
  struct Rule {
    std::vector<int> antecedent;  // set index per input, -1 = don't care
    std::size_t consequent;
    double weight;
  };

  FuzzyEngineSpec spec_;
  std::vector<Variable> inputs_;
  Variable output_;
  std::vector<Rule> rules_;
  std::vector<std::size_t> input_offset_;
  // Buffers, sized once.
  std::vector<double> universe_in_;
  std::vector<double> input_mu_;
  std::vector<double> rule_strength_;
  std::vector<double> set_level_;
  std::vector<double> samples_;     // output universe samples
  std::vector<double> weights_;     // trapezoidal-rule weights
  std::vector<double> output_mu_;   // [set * resolution + k]
  std::vector<double> aggregated_;
  double crisp_ = 0.0;
};

// The paper's controller (seed 001, Figs. 3-4 and the rule table) as data.
// Input 1 (theta of the table): 9 sets NVL NL NM NS ZE PS PM PL PVL on
// [-1, 1]: triangles with peaks 0.2 apart and base half-width 0.2, the two
// outermost trapezoid shoulders (flat from the range end to +-0.8), so the
// sets form a partition of unity. Input 2 (theta-double-dot): N, ZE, P:
// trapezoid shoulders flat beyond +-0.5, ZE a triangle of half-width 0.5.
// Output: the 9 sets of input 1. Figs. 3-4 are not in the text, only "the
// level surface at the tip of the trapezium in the trapezoidal MFs produces
// a stronger control force": these shapes are a choice in that spirit.
// Rule table (27 rules, rows theta, columns N / ZE / P):
//   NVL: NVL NVL NL    NL: NVL NL NM    NM: NL NM NS    NS: NM NS NS    ZE: ZE ZE ZE
//   PS:  PM  PS  PS    PM: PL  PM PS    PL: PVL PL PM   PVL: PVL PVL PL
// The printed "NNL" (NL, N) is not a set; read as NVL, the one-step shift
// its column makes everywhere else. As printed the table is odd in theta
// alone (f(-x1, x2) = -f(x1, x2)): the second input only enlarges (N) or
// shrinks (P) the magnitude whatever the sign of the first, so it is not
// odd under negating both inputs. kOddSymmetric keeps the printed rows
// NVL..ZE and mirrors them, f(x1, x2) = -f(-x1, -x2), for the rows PS..PVL.
enum class PaperRuleTable { kAsPrinted, kOddSymmetric };

// Physical values mapped to the universe edge +-1 (inputs saturate there).
// Chosen as the standard normalisation of a fuzzy controller to the range
// its signals take: the largest body corner velocity (0.10 m/s) and
// acceleration (3.9 m/s^2) of the passive pitch-plane car on the paper's bump
// (a0 0.05 m, lambda0 0.2 m, 20 m/s), rounded. Not tuned to a result.
struct PaperFuzzyScaling {
  double input1_range = 0.10;   // [m/s] body corner velocity (or [m] displacement)
  double input2_range = 4.0;    // [m/s^2] body corner acceleration
  double force_limit = 2000.0;  // [N] output scale: universe +-1 -> +-force_limit (kDefaultSuspensionForceLimit)
};

FuzzyEngineSpec paper_fuzzy_spec(const PaperFuzzyScaling& scaling = {},
                                 PaperRuleTable table = PaperRuleTable::kAsPrinted);

}  // namespace rigctl
