#include "config/suspension_controller_reader.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<std::string> split_words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// One linguistic variable: universe, scale and its named sets in file order.
LinguisticVariableSpec read_variable(ConfigReader r, const std::string& name) {
  LinguisticVariableSpec v;
  v.name = name;
  const auto universe = r.numbers("universe", 2, 2);
  if (!(universe[0] < universe[1])) r.fail("universe", "must be [min, max] with min < max");
  v.min = universe[0];
  v.max = universe[1];
  v.scale = r.number("scale", 1e-12, 1e12);
  auto sets = r.child("sets");
  const auto names = sets.keys();
  if (names.empty()) r.fail("sets", "needs at least one membership function");
  for (const auto& set_name : names) {
    auto s = sets.child(set_name);
    MembershipFunctionSpec mf;
    mf.name = set_name;
    const bool tri = s.has("triangle");
    const bool trap = s.has("trapezoid");
    if (tri == trap) {
      s.fail(tri ? "triangle" : "trapezoid",
             "give exactly one shape: {triangle: [a, b, c]} or {trapezoid: [a, b, c, d]}");
    }
    if (tri) {
      mf.shape = MembershipShape::kTriangle;
      mf.points = s.numbers("triangle", 3, 3);
    } else {
      mf.shape = MembershipShape::kTrapezoid;
      mf.points = s.numbers("trapezoid", 4, 4);
    }
    try {
      MembershipFunction::from_spec(mf);
    } catch (const std::invalid_argument& e) {
      s.fail(tri ? "triangle" : "trapezoid", e.what());
    }
    s.reject_unknown_keys();
    v.sets.push_back(std::move(mf));
  }
  sets.reject_unknown_keys();
  r.reject_unknown_keys();
  return v;
}

bool has_set(const LinguisticVariableSpec& v, const std::string& name) {
  return std::any_of(v.sets.begin(), v.sets.end(), [&](const auto& s) { return s.name == name; });
}

std::vector<std::string> set_names(const LinguisticVariableSpec& v) {
  std::vector<std::string> out;
  for (const auto& s : v.sets) out.push_back(s.name);
  return out;
}

}  // namespace

FuzzyEngineSpec read_fuzzy_engine(ConfigReader r, FuzzyFirstInput& first_input) {
  FuzzyEngineSpec spec;
  first_input = r.choice("first_input", {"velocity", "displacement"}) == "velocity" ? FuzzyFirstInput::kVelocity
                                                                                    : FuzzyFirstInput::kDisplacement;
  spec.resolution = static_cast<int>(r.integer("resolution", 3, 1000001));

  auto inputs = r.child("inputs");
  const auto input_names = inputs.keys();
  if (input_names.size() != 2) {
    r.fail("inputs", "the suspension controller takes exactly two inputs (body corner velocity or displacement "
                     "error, then acceleration error), got " + std::to_string(input_names.size()));
  }
  for (const auto& name : input_names) spec.inputs.push_back(read_variable(inputs.child(name), name));
  inputs.reject_unknown_keys();

  auto output = r.child("output");
  const auto output_names = output.keys();
  if (output_names.size() != 1) r.fail("output", "give exactly one output variable");
  spec.output = read_variable(output.child(output_names[0]), output_names[0]);
  output.reject_unknown_keys();

  // The rule table: a row per input-1 set, a column per input-2 set.
  auto rules = r.child("rules");
  const auto& rows = spec.inputs[0].sets;
  const auto& cols = spec.inputs[1].sets;
  std::vector<std::vector<std::string>> table;
  for (const auto& row : rows) {
    const auto cells = split_words(rules.text(row.name));
    if (cells.size() != cols.size()) {
      rules.fail(row.name, "expected " + std::to_string(cols.size()) + " output sets (one per set of input '" +
                               spec.inputs[1].name + "': " + joined(set_names(spec.inputs[1])) + "), got " +
                               std::to_string(cells.size()));
    }
    for (const auto& cell : cells) {
      if (cell != "-" && !has_set(spec.output, cell)) {
        rules.fail(row.name, "unknown output set '" + cell + "' (sets of '" + spec.output.name +
                                 "': " + joined(set_names(spec.output)) + "; '-' for no rule)");
      }
    }
    table.push_back(cells);
  }
  rules.reject_unknown_keys();
  // Numbered column by column, as seed 001 numbers its rules.
  for (std::size_t c = 0; c < cols.size(); ++c) {
    for (std::size_t k = 0; k < rows.size(); ++k) {
      if (table[k][c] == "-") continue;
      spec.rules.push_back({{rows[k].name, cols[c].name}, table[k][c], 1.0});
    }
  }
  if (spec.rules.empty()) r.fail("rules", "the table holds no rule");
  try {
    FuzzyEngine check(spec);
  } catch (const std::invalid_argument& e) {
    r.fail("rules", e.what());
  }
  r.reject_unknown_keys();
  return spec;
}

void read_suspension_controller(ConfigReader& r, SuspensionControllerSettings& s) {
  s.output_1 = r.text("output_1");
  s.output_2 = r.text("output_2");
  s.force_limit = r.number("force_limit_n", 1.0, 1e6);
  s.fuzzy = read_fuzzy_engine(r.child("fuzzy"), s.fuzzy_first_input);
  auto sky = r.child("skyhook");
  s.skyhook_c_sky = sky.number("c_sky_n_s_per_m", 0.0, 1e7);
  sky.reject_unknown_keys();
  auto lqr = r.child("lqr");
  // Bryson's rule: each weight is the largest acceptable value of its quantity.
  s.lqr.heave_acceleration = lqr.number("heave_acceleration_m_s2", 1e-9, kInf);
  s.lqr.angle_acceleration = lqr.number("angle_acceleration_rad_s2", 1e-9, kInf);
  s.lqr.suspension_travel = lqr.number("suspension_travel_m", 1e-9, kInf);
  s.lqr.tyre_deflection = lqr.number("tyre_deflection_m", 1e-9, kInf);
  s.lqr.heave = lqr.number("heave_m", 1e-9, kInf);
  s.lqr.angle = lqr.number("angle_rad", 1e-9, kInf);
  s.lqr.force = lqr.number("force_n", 1e-9, kInf);
  lqr.reject_unknown_keys();
}

SuspensionReportConfig read_suspension_report(ConfigReader r) {
  SuspensionReportConfig c;
  c.settling_band_fraction = r.number("settling_band_percent", 0.0, 100.0) / 100.0;
  c.settling_min_band = r.number("settling_min_band_m", 0.0, 1.0);
  if (c.settling_band_fraction == 0.0 && c.settling_min_band == 0.0) {
    r.fail("settling_band_percent", "the settling band would be zero: give a percentage or settling_min_band_m");
  }
  r.reject_unknown_keys();
  return c;
}

SuspensionOptimizeConfig read_suspension_optimize(ConfigReader r) {
  SuspensionOptimizeConfig c;
  c.algorithm = r.choice("algorithm", {"isres", "crs2_lm"});
  c.controller = read_controller_kind(r, "controller", RigKind::kHalfCar);
  c.evaluations = static_cast<int>(r.integer("evaluations", 1, 1000000));
  c.seed = static_cast<uint64_t>(r.integer("seed", 0, std::numeric_limits<int64_t>::max()));
  c.duration_s = r.number("duration_s", 0.01, 3600.0);
  auto w = r.child("weights");
  c.weight_comfort = w.number("comfort", 0.0, 1e6);
  c.weight_tyre = w.number("tyre_deflection", 0.0, 1e6);
  c.weight_travel = w.number("suspension_travel", 0.0, 1e6);
  if (!(c.weight_comfort + c.weight_tyre + c.weight_travel > 0.0)) w.fail("comfort", "at least one weight must be positive");
  w.reject_unknown_keys();
  c.travel_limit = r.number("travel_limit_m", 1e-4, 1.0);
  c.penalty = r.number("penalty", 0.0, 1e9);
  auto v = r.child("variables");
  for (const auto& name : v.keys()) {
    const auto& known = optimize_variable_names();
    if (std::find(known.begin(), known.end(), name) == known.end()) {
      v.fail(name, "unknown design variable (known: " + joined(known) + ")");
    }
    const auto range = v.numbers(name, 2, 2, 0.0, 1e9);
    if (!(range[0] < range[1])) v.fail(name, "bounds must be [min, max] with min < max");
    c.variables.push_back({name, range[0], range[1]});
  }
  if (c.variables.empty()) r.fail("variables", "give at least one design variable with its bounds");
  r.reject_unknown_keys();
  return c;
}

}  // namespace rigctl
