#include "tools/common/json_text.hpp"
#include "tools/suspension/optimize_command.hpp"

#include <unistd.h>

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/suspension/compare_command.hpp"

namespace rigctl {

namespace fs = std::filesystem;

namespace {

double& field(HalfCarParams& p, const std::string& name) {
  if (name == "spring_1") return p.spring_1;
  if (name == "spring_2") return p.spring_2;
  if (name == "damper_1") return p.damper_1;
  if (name == "damper_2") return p.damper_2;
  throw std::invalid_argument("unknown design variable " + name);
}

// The plant key a design variable sets, for messages.
std::string plant_key(const std::string& name) {
  const std::string corner = name.back() == '1' ? "corner_1" : "corner_2";
  return "plant." + corner + (name.rfind("spring", 0) == 0 ? ".spring_n_per_m" : ".damper_n_s_per_m");
}

double rms_pair(const std::array<std::vector<double>, 2>& x) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& v : x) {
    for (double e : v) sum += e * e;
    n += v.size();
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

double peak_pair(const std::array<std::vector<double>, 2>& x) { return std::max(peak_abs(x[0]), peak_abs(x[1])); }

std::string result_name(nlopt::result r) {
  switch (r) {
    case nlopt::FAILURE: return "FAILURE";
    case nlopt::INVALID_ARGS: return "INVALID_ARGS";
    case nlopt::OUT_OF_MEMORY: return "OUT_OF_MEMORY";
    case nlopt::ROUNDOFF_LIMITED: return "ROUNDOFF_LIMITED";
    case nlopt::FORCED_STOP: return "FORCED_STOP";
    case nlopt::SUCCESS: return "SUCCESS";
    case nlopt::STOPVAL_REACHED: return "STOPVAL_REACHED";
    case nlopt::FTOL_REACHED: return "FTOL_REACHED";
    case nlopt::XTOL_REACHED: return "XTOL_REACHED";
    case nlopt::MAXEVAL_REACHED: return "MAXEVAL_REACHED";
    case nlopt::MAXTIME_REACHED: return "MAXTIME_REACHED";
    default: return "UNKNOWN";
  }
}

class Problem {
 public:
  Problem(const RigConfig& config, const SuspensionOptimizeConfig& settings, std::ostream& progress, bool show)
      : config_(config), s_(settings), progress_(progress), show_(show), tty_(show && ::isatty(STDERR_FILENO) != 0),
        start_(std::chrono::steady_clock::now()) {}

  // Physical values from the search's [0, 1] coordinates.
  std::vector<double> physical(const std::vector<double>& u) const {
    std::vector<double> v(u.size());
    for (std::size_t i = 0; i < u.size(); ++i) {
      const auto& var = s_.variables[i];
      v[i] = var.min + std::clamp(u[i], 0.0, 1.0) * (var.max - var.min);
    }
    return v;
  }

  // One simulation of a design; the cost needs the reference (initial) set.
  DesignEvaluation simulate(const std::vector<double>& values) const {
    RigConfig c = config_;
    for (std::size_t i = 0; i < values.size(); ++i) field(c.half_car, s_.variables[i].name) = values[i];
    const SuspensionRecording rec = run_half_car(c, s_.controller, s_.duration_s, false);
    DesignEvaluation e;
    e.values = values;
    e.metrics = compute_suspension_metrics(rec.run);
    e.wk_rms_acc = e.metrics.wk_rms_acc;
    e.rms_tyre_deflection = rms_pair(rec.run.tyre_deflection);
    e.rms_travel = rms_pair(rec.run.travel);
    e.peak_travel = peak_pair(rec.run.travel);
    e.faulted = rec.loop.final_state == RigState::kFaulted;
    e.feasible = !e.faulted && e.peak_travel <= s_.travel_limit;
    return e;
  }

  void set_reference(const DesignEvaluation& initial) {
    ref_ = initial;
    auto nonzero = [](double v) { return v > 0.0 ? v : 1.0; };
    ref_.wk_rms_acc = nonzero(ref_.wk_rms_acc);
    ref_.rms_tyre_deflection = nonzero(ref_.rms_tyre_deflection);
    ref_.rms_travel = nonzero(ref_.rms_travel);
  }

  // The weighted cost without any constraint term.
  double weighted(const DesignEvaluation& e) const {
    return s_.weight_comfort * e.wk_rms_acc / ref_.wk_rms_acc +
           s_.weight_tyre * e.rms_tyre_deflection / ref_.rms_tyre_deflection +
           s_.weight_travel * e.rms_travel / ref_.rms_travel;
  }

  // Relative excess of the travel limit (<= 0: within it).
  double violation(const DesignEvaluation& e) const {
    return e.faulted ? 1.0 : e.peak_travel / s_.travel_limit - 1.0;
  }

  // Evaluates (with a one-entry cache: ISRES asks for the objective and the
  // constraint at the same point one after the other).
  const DesignEvaluation& evaluate(const std::vector<double>& u) {
    if (have_last_ && u == last_u_) return last_;
    // CRS2 may try a point or two past maxeval before it checks: the budget
    // is the configured number of simulations, exactly.
    if (count_ >= s_.evaluations) throw nlopt::forced_stop();
    last_u_ = u;
    last_ = simulate(physical(u));
    last_.cost = weighted(last_);
    have_last_ = true;
    ++count_;
    if (last_.feasible && (!have_best_ || last_.cost < best_.cost)) {
      best_ = last_;
      have_best_ = true;
    }
    report(false);
    return last_;
  }

  double objective(const std::vector<double>& u) {
    const DesignEvaluation& e = evaluate(u);
    if (s_.algorithm == "crs2_lm") {
      // The paper's penalty function: the constrained problem made unconstrained.
      return e.cost + s_.penalty * std::max(0.0, violation(e)) + (e.faulted ? 1e3 : 0.0);
    }
    return e.cost + (e.faulted ? 1e3 : 0.0);
  }

  double constraint(const std::vector<double>& u) { return violation(evaluate(u)); }

  void offer(const DesignEvaluation& e) {
    if (e.feasible && (!have_best_ || e.cost < best_.cost)) {
      best_ = e;
      have_best_ = true;
    }
  }

  void report(bool final) {
    if (!show_) return;
    const int every = std::max(1, s_.evaluations / 20);
    if (!final && !tty_ && count_ % every != 0) return;
    if (final && !tty_ && count_ % every == 0) return;  // the last line is already out
    char line[200];
    std::snprintf(line, sizeof line, "optimize: %d/%d evaluations, best cost %.4f (initial %.4f), elapsed %.1f s",
                  count_, s_.evaluations, have_best_ ? best_.cost : std::numeric_limits<double>::quiet_NaN(),
                  ref_.cost, elapsed());
    if (tty_) {
      progress_ << "\r" << line << (final ? "\n" : "") << std::flush;
    } else {
      progress_ << line << "\n" << std::flush;
    }
  }

  double elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  int count() const { return count_; }
  bool has_best() const { return have_best_; }
  const DesignEvaluation& best() const { return best_; }

 private:
  const RigConfig& config_;
  const SuspensionOptimizeConfig& s_;
  std::ostream& progress_;
  bool show_, tty_;
  std::chrono::steady_clock::time_point start_;
  DesignEvaluation ref_, last_, best_;
  std::vector<double> last_u_;
  bool have_last_ = false, have_best_ = false;
  int count_ = 0;
};

double objective_thunk(const std::vector<double>& u, std::vector<double>& grad, void* data) {
  (void)grad;  // derivative-free methods only
  return static_cast<Problem*>(data)->objective(u);
}

double constraint_thunk(const std::vector<double>& u, std::vector<double>& grad, void* data) {
  (void)grad;
  return static_cast<Problem*>(data)->constraint(u);
}

void write_evaluation(std::ostream& js, const char* name, const DesignEvaluation& e,
                      const std::vector<OptimizeVariable>& vars, const char* tail) {
  js << "  " << json_string(name) << ": {\n    \"parameters\": {";
  for (std::size_t i = 0; i < vars.size(); ++i) {
    js << (i ? ", " : "") << json_string(vars[i].name) << ": " << json_number(e.values[i]);
  }
  const auto& m = e.metrics;
  js << "},\n    \"cost\": " << json_number(e.cost) << ",\n    \"feasible\": " << (e.feasible ? "true" : "false")
     << ",\n    \"wk_rms_acc_m_s2\": " << json_number(e.wk_rms_acc)
     << ",\n    \"rms_tyre_deflection_m\": " << json_number(e.rms_tyre_deflection)
     << ",\n    \"rms_suspension_travel_m\": " << json_number(e.rms_travel)
     << ",\n    \"peak_suspension_travel_m\": " << json_number(e.peak_travel)
     << ",\n    \"peak_z_s_m\": " << json_number(m.peak_z_s) << ",\n    \"peak_acc_m_s2\": " << json_number(m.peak_acc)
     << ",\n    \"rms_acc_m_s2\": " << json_number(m.rms_acc)
     << ",\n    \"settling_time_s\": " << json_number(m.settling_time)
     << ",\n    \"peak_tyre_deflection_m\": [" << json_number(m.peak_tyre_deflection[0]) << ", "
     << json_number(m.peak_tyre_deflection[1]) << "]"
     << ",\n    \"time_without_contact_s\": [" << json_number(m.time_without_contact[0]) << ", "
     << json_number(m.time_without_contact[1]) << "]\n  }" << tail << "\n";
}

// The initial design, the config's plant, scaled to 0..1 within the
// variables' bounds; a config value outside them is refused.
std::vector<double> initial_design(const RigConfig& config, const SuspensionOptimizeConfig& s, const std::string& config_path) {
  std::vector<double> x0;
  HalfCarParams initial_params = config.half_car;  // field() reads through a mutable reference
  for (const auto& v : s.variables) {
    const double value = field(initial_params, v.name);
    if (value < v.min || value > v.max) {
      throw ConfigError(config_path + ": " + plant_key(v.name) + ": the initial design " +
                        json_number(value) + " is outside optimize.variables." + v.name + " [" + json_number(v.min) +
                        ", " + json_number(v.max) + "]");
    }
    x0.push_back((value - v.min) / (v.max - v.min));
  }
  return x0;
}

// NLopt's search from x0 within the evaluation budget; the best feasible
// design found stands whatever way the search ends.
void search(Problem& problem, const SuspensionOptimizeConfig& s, const std::vector<double>& x0, OptimizeResult& result) {
  const auto n = static_cast<unsigned>(s.variables.size());
  nlopt::opt opt(s.algorithm == "isres" ? nlopt::GN_ISRES : nlopt::GN_CRS2_LM, n);
  nlopt::srand(static_cast<unsigned long>(s.seed));
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_min_objective(objective_thunk, &problem);
  if (s.algorithm == "isres") opt.add_inequality_constraint(constraint_thunk, &problem, 0.0);
  opt.set_maxeval(s.evaluations);
  std::vector<double> x = x0;
  double f = 0.0;
  try {
    result.nlopt_result = result_name(opt.optimize(x, f));
  } catch (const nlopt::forced_stop&) {
    result.nlopt_result = result_name(nlopt::MAXEVAL_REACHED);  // our budget, enforced above
  } catch (const std::exception& e) {
    // NLopt ends some searches with an exception (e.g. roundoff limited);
    // the best design found so far stands.
    result.nlopt_result = std::string("stopped: ") + e.what();
  }
  result.evaluations = problem.count();
  problem.report(true);
  result.elapsed_s = problem.elapsed();
  result.best = problem.has_best() ? problem.best() : result.initial;
}

// The summary: the search's end, the variables and the metrics, initial beside optimum.
void print_summary(const OptimizeResult& result, const SuspensionOptimizeConfig& s, std::ostream& out) {
  out << "  NLopt: " << result.nlopt_result << " after " << result.evaluations << " evaluations, "
      << std::fixed << std::setprecision(1) << result.elapsed_s << " s\n";
  out << "\n" << std::left << std::setw(12) << "variable" << std::right << std::setw(14) << "initial"
      << std::setw(14) << "optimum" << std::setw(26) << "bounds (Table 2)" << "\n";
  for (std::size_t i = 0; i < s.variables.size(); ++i) {
    const auto& v = s.variables[i];
    std::ostringstream bounds;
    bounds << "[" << std::fixed << std::setprecision(0) << v.min << ", " << v.max << "]";
    out << std::left << std::setw(12) << v.name << std::right << std::fixed << std::setprecision(1) << std::setw(14)
        << result.initial.values[i] << std::setw(14) << result.best.values[i] << std::setw(26) << bounds.str() << "\n";
  }
  auto row = [&](const char* label, double scale, double a, double b, int digits) {
    out << std::left << std::setw(34) << label << std::right << std::fixed << std::setprecision(digits)
        << std::setw(12) << scale * a << std::setw(12) << scale * b << "\n";
  };
  out << "\n" << std::left << std::setw(34) << "" << std::right << std::setw(12) << "initial" << std::setw(12)
      << "optimum" << "\n";
  row("cost", 1.0, result.initial.cost, result.best.cost, 4);
  row("Wk RMS body acceleration [m/s^2]", 1.0, result.initial.wk_rms_acc, result.best.wk_rms_acc, 4);
  row("RMS tyre deflection [mm]", 1e3, result.initial.rms_tyre_deflection, result.best.rms_tyre_deflection, 3);
  row("RMS suspension travel [mm]", 1e3, result.initial.rms_travel, result.best.rms_travel, 3);
  row("peak suspension travel [mm]", 1e3, result.initial.peak_travel, result.best.peak_travel, 2);
  row("peak body displacement [mm]", 1e3, result.initial.metrics.peak_z_s, result.best.metrics.peak_z_s, 3);
  row("peak body acceleration [m/s^2]", 1.0, result.initial.metrics.peak_acc, result.best.metrics.peak_acc, 3);
}

// The optimum's JSON file (result.out_path).
void write_optimum(const OptimizeResult& result, const OptimizeOptions& options, const SuspensionOptimizeConfig& s) {
  if (!fs::path(result.out_path).parent_path().empty()) fs::create_directories(fs::path(result.out_path).parent_path());
  std::ofstream js(result.out_path);
  if (!js) throw std::runtime_error(result.out_path + ": cannot create");
  bool within = true;
  for (std::size_t i = 0; i < s.variables.size(); ++i) {
    within = within && result.best.values[i] >= s.variables[i].min && result.best.values[i] <= s.variables[i].max;
  }
  js << "{\n  \"rig\": \"half_car\",\n  \"config\": " << json_string(options.config_path)
     << ",\n  \"case\": " << json_string(options.case_name) << ",\n  \"algorithm\": " << json_string(s.algorithm)
     << ",\n  \"controller\": " << json_string(std::string(to_string(s.controller))) << ",\n  \"seed\": " << s.seed
     << ",\n  \"evaluations\": " << result.evaluations << ",\n  \"max_evaluations\": " << s.evaluations
     << ",\n  \"nlopt_result\": " << json_string(result.nlopt_result)
     << ",\n  \"elapsed_s\": " << json_number(result.elapsed_s) << ",\n  \"duration_s\": " << json_number(s.duration_s)
     << ",\n  \"weights\": {\"comfort\": " << json_number(s.weight_comfort)
     << ", \"tyre_deflection\": " << json_number(s.weight_tyre)
     << ", \"suspension_travel\": " << json_number(s.weight_travel) << "}"
     << ",\n  \"travel_limit_m\": " << json_number(s.travel_limit) << ",\n  \"bounds\": {";
  for (std::size_t i = 0; i < s.variables.size(); ++i) {
    js << (i ? ", " : "") << json_string(s.variables[i].name) << ": [" << json_number(s.variables[i].min) << ", "
       << json_number(s.variables[i].max) << "]";
  }
  js << "},\n  \"within_bounds\": " << (within ? "true" : "false") << ",\n";
  write_evaluation(js, "initial", result.initial, s.variables, ",");
  write_evaluation(js, "optimum", result.best, s.variables, "");
  js << "}\n";
  js.close();
  if (!js) throw std::runtime_error(result.out_path + ": write failed");
}

}  // namespace

OptimizeResult run_optimize(const OptimizeOptions& options, std::ostream& out, std::ostream& progress) {
  const RigConfig config = load_rig_config(options.config_path, options.case_name);
  if (config.rig != RigKind::kHalfCar) {
    throw ConfigError(options.config_path + ": rig: `rigctl optimize` is for the half_car rig, this config is " +
                      std::string(to_string(config.rig)));
  }
  OptimizeResult result;
  result.settings = config.suspension_optimize;
  auto& s = result.settings;
  if (options.evaluations) {
    if (*options.evaluations < 1) throw std::runtime_error("--evaluations must be at least 1");
    s.evaluations = *options.evaluations;
  }
  const std::vector<double> x0 = initial_design(config, s, options.config_path);
  result.out_path = options.out_path.empty()
                        ? (fs::path(config.telemetry.log_dir) /
                           ("half_car-optimum" + (options.case_name.empty() ? "" : "-" + options.case_name) + ".json"))
                              .string()
                        : options.out_path;

  out << "rigctl optimize: half_car from " << options.config_path
      << (options.case_name.empty() ? "" : " case " + options.case_name) << ": " << s.algorithm << ", "
      << s.evaluations << " evaluations of " << s.duration_s << " s (" << s.controller << " controller), seed "
      << s.seed << "\n  cost = " << s.weight_comfort << " Wk/Wk0 + " << s.weight_tyre << " T/T0 + "
      << s.weight_travel << " S/S0, peak |travel| <= " << s.travel_limit << " m\n";
  out.flush();

  Problem problem(config, s, progress, options.progress);
  {
    DesignEvaluation initial = problem.simulate(problem.physical(x0));
    problem.set_reference(initial);
    initial.cost = problem.weighted(initial);
    problem.set_reference(initial);
    result.initial = initial;
    problem.offer(initial);
  }
  search(problem, s, x0, result);
  print_summary(result, s, out);
  write_optimum(result, options, s);
  out << "\n  optimum: " << result.out_path << "\n";
  out.flush();
  return result;
}

}  // namespace rigctl
