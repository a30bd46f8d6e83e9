// Plant section: each simulated plant run for 20 s of rig time on a recorded
// command sequence (the rig's own closed loop, replayed open loop so every
// integrator sees the same input): real-time factor of the fixed-step RK4 the
// loop uses, at its configured sub-steps and at 1/4..4x of them, and its
// error against Boost.Odeint's adaptive Dormand-Prince at 1e-10 with located
// mode switches, whose own run time is measured the same way.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include "config/rig_config.hpp"
#include "plant/quarter_car/quarter_car_step_size.hpp"
#include "rt/loop_clock.hpp"
#include "rt/loop/rig_loop.hpp"
#include "tools/bench/sections.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl::bench {

namespace {

class RecordingSink final : public TelemetrySink {
 public:
  explicit RecordingSink(CommandSeries& out) : out_(out) {}
  bool push(const TelemetryRecord& r) noexcept override {
    if (r.has_sample && out_.size() < out_.capacity()) out_.push_back({r.command.value[0], r.command.value[1]});
    return true;
  }

 private:
  CommandSeries& out_;
};

}  // namespace

CommandSeries closed_loop_commands(const RigConfig& config, int64_t ticks) {
  AssembledRig rig = assemble_rig(config);
  CommandSeries u;
  u.reserve(static_cast<std::size_t>(ticks));
  RecordingSink sink(u);
  VirtualClock clock;
  LoopOptions o;
  o.period_ns = std::llround(config.loop.period_s * 1e9);
  o.overrun_policy = config.loop.overrun_policy;
  o.max_ticks = ticks;
  o.start_from_input = rig.profile_start_input;
  o.timing_every_ticks = 0;
  rig.driver->start();
  // The rig as `rigctl run --fast` runs it: the configured detectors and
  // state machine, the automatic sequence (no operator here).
  rig.safety.auto_sequence = true;
  RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, sink, clock, o, rig.safety);
  const std::atomic<bool> never{false};
  loop.run(never);
  rig.driver->stop();
  // A run that ended early (a limit) holds the safe command for the rest.
  while (static_cast<int64_t>(u.size()) < ticks) u.push_back({0.0, 0.0});
  return u;
}

PlantInputs::PlantInputs(const Context& ctx, double seconds)
    : qc(load_rig_config(ctx.quarter_car_config)),
      pn(load_rig_config(ctx.pneumatic_config)),
      T(qc.loop.period_s),
      ticks(static_cast<int64_t>(std::llround(seconds / T))),
      qc_u(closed_loop_commands(qc, ticks)),
      pn_u(closed_loop_commands(pn, static_cast<int64_t>(std::llround(seconds / pn.loop.period_s)))),
      passive(static_cast<std::size_t>(ticks), HeldCommand{0.0, 0.0}) {
  iso.road.kind = RoadKind::kIso8608;
  iso.road.iso.road_class = IsoRoadClass::kC;
}

namespace {

using Clock = std::chrono::steady_clock;

struct FixedRun {
  int substeps = 0;
  double wall_s = 0.0;  // best of the repetitions
  std::vector<std::vector<double>> at;
};

// The plant's own advance() period by period; states captured after each.
template <class Plant, class Params>
FixedRun run_fixed(const Params& params, int substeps, const CommandSeries& u, double period_s, int repetitions) {
  Params p = params;
  p.substeps = substeps;
  FixedRun r;
  r.substeps = substeps;
  r.wall_s = std::numeric_limits<double>::infinity();
  for (int rep = 0; rep < repetitions; ++rep) {
    Plant plant(p);
    plant.reset();
    const std::size_t n = plant.commands().size();
    std::vector<std::vector<double>> at;
    at.reserve(u.size());
    const auto start = Clock::now();
    for (const auto& c : u) {
      plant.advance(std::span<const double>(c.data(), n), period_s);
      at.push_back(state_vector(plant.state()));
    }
    const double wall = std::chrono::duration<double>(Clock::now() - start).count();
    r.wall_s = std::min(r.wall_s, wall);
    r.at = std::move(at);
    if (wall > 1.0) break;  // long enough to time once
  }
  return r;
}

struct ErrorSummary {
  std::vector<double> max_abs, rms, range;
  double worst_normalized = 0.0;
  std::string worst_component;
};

ErrorSummary compare(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& ref,
                     const std::vector<std::string>& names) {
  ErrorSummary e;
  const std::size_t n = names.size();
  e.max_abs.assign(n, 0.0);
  e.rms.assign(n, 0.0);
  e.range.assign(n, 0.0);
  std::vector<double> lo(n, std::numeric_limits<double>::infinity()), hi(n, -std::numeric_limits<double>::infinity());
  const std::size_t k_end = std::min(a.size(), ref.size());
  for (std::size_t k = 0; k < k_end; ++k) {
    for (std::size_t j = 0; j < n; ++j) {
      const double d = a[k][j] - ref[k][j];
      const double ad = std::isfinite(d) ? std::abs(d) : std::numeric_limits<double>::infinity();
      e.max_abs[j] = std::max(e.max_abs[j], ad);
      e.rms[j] += d * d;
      lo[j] = std::min(lo[j], ref[k][j]);
      hi[j] = std::max(hi[j], ref[k][j]);
    }
  }
  e.worst_normalized = 0.0;
  for (std::size_t j = 0; j < n; ++j) {
    e.rms[j] = k_end > 0 ? std::sqrt(e.rms[j] / static_cast<double>(k_end)) : 0.0;
    e.range[j] = hi[j] - lo[j];
    if (e.range[j] > 0.0) {
      const double norm = e.max_abs[j] / e.range[j];
      if (!(norm <= e.worst_normalized)) {
        e.worst_normalized = norm;
        e.worst_component = names[j];
      }
    }
  }
  return e;
}

Json error_json(const ErrorSummary& e, const std::vector<std::string>& names) {
  Json j = Json::object();
  Json per = Json::object();
  for (std::size_t i = 0; i < names.size(); ++i) {
    Json c = Json::object();
    c["max_abs"] = e.max_abs[i];
    c["rms"] = e.rms[i];
    c["reference_range"] = e.range[i];
    c["max_abs_over_range"] = ratio(e.max_abs[i], e.range[i]);
    per[names[i]] = c;
  }
  j["worst_max_abs_over_range"] = e.worst_normalized;
  j["worst_component"] = e.worst_component;
  j["components"] = per;
  return j;
}

Json stats_json(const ReferenceStats& s, double sim_s) {
  Json j = Json::object();
  j["method"] = "Boost.Odeint runge_kutta_dopri5, controlled (adaptive), mode switches located by bisection";
  j["tolerance_abs_rel"] = s.tolerance;
  j["wall_s"] = s.wall_s;
  j["real_time_factor"] = ratio(sim_s, s.wall_s);
  j["steps"] = s.steps;
  j["rejected_steps"] = s.rejected;
  j["rhs_evaluations"] = s.rhs_evaluations;
  j["mode_switch_events"] = s.events;
  j["mean_step_us"] = ratio(sim_s * 1e6, static_cast<double>(s.steps));
  return j;
}

struct Case {
  std::string name;
  std::string description;
  std::string output;  // the headline state component
  int default_substeps = 0;
  std::function<FixedRun(int substeps, int repetitions)> fixed;
  std::function<ReferenceResult(double tolerance)> reference;
  std::function<double(const FixedRun&, int& checked)> agreement;
  std::vector<std::string> names;
};

template <class State>
std::vector<State> every(const std::vector<State>& all, std::size_t stride) {
  std::vector<State> out;
  for (std::size_t i = 0; i < all.size(); i += stride) out.push_back(all[i]);
  return out;
}

// Plant states along a run, for the agreement check (the fixed run keeps vectors only).
template <class Plant, class Params>
std::pair<std::vector<decltype(std::declval<Plant>().state())>, std::vector<HeldCommand>> sample_states(
    const Params& params, const CommandSeries& u, double period_s, std::size_t stride) {
  Plant plant(params);
  plant.reset();
  const std::size_t n = plant.commands().size();
  std::vector<decltype(plant.state())> states;
  std::vector<HeldCommand> cmds;
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (k % stride == 0) {
      states.push_back(plant.state());
      cmds.push_back(u[k]);
    }
    plant.advance(std::span<const double>(u[k].data(), n), period_s);
  }
  return {states, cmds};
}

// The section's settings: full or --quick.
struct PlantRunSettings {
  double sim_s = 0.0;
  double tolerance = 0.0;
  int repetitions = 0;
  double T = 0.0;
};

// The four plants, each with its fixed-step runs, its reference and its
// right-hand side check; they read `in`, which must outlive them.
std::vector<Case> plant_cases(const PlantInputs& in, const std::atomic<bool>& stop) {
  std::vector<Case> cases;
  const double T = in.T;
  cases.push_back({"quarter_car", "config/quarter_car.yaml plant (hydraulics, leakage, bearing stick-slip), commands of its PI closed loop on the 50 mm step test",
                   "x_r", quarter_car_substeps(in.qc.quarter_car, T),
                   [&in, T](int n, int reps) { return run_fixed<QuarterCarPlant>(in.qc.quarter_car, n, in.qc_u, T, reps); },
                   [&in, T, &stop](double tol) { return reference_quarter_car(in.qc.quarter_car, in.qc_u, T, tol, stop); },
                   [&in, T](const FixedRun& f, int& checked) {
                     const auto [s, c] = sample_states<QuarterCarPlant>(in.qc.quarter_car, in.qc_u, T, 50);
                     return rhs_agreement_quarter_car(in.qc.quarter_car, s, c, T / f.substeps, checked);
                   },
                   quarter_car_state_names()});
  const double Tp = in.pn.loop.period_s;
  cases.push_back({"pneumatic_rotary", "config/pneumatic_rotary.yaml plant (dither, bladder hysteresis stick-slip), commands of its PVP closed loop (fig4c)",
                   "theta", in.pn.pneumatic_rotary.substeps,
                   [&in, Tp](int n, int reps) { return run_fixed<PneumaticRotaryPlant>(in.pn.pneumatic_rotary, n, in.pn_u, Tp, reps); },
                   [&in, Tp, &stop](double tol) { return reference_pneumatic(in.pn.pneumatic_rotary, in.pn_u, Tp, tol, stop); },
                   [&in, Tp](const FixedRun& f, int& checked) {
                     const auto [s, c] = sample_states<PneumaticRotaryPlant>(in.pn.pneumatic_rotary, in.pn_u, Tp, 50);
                     return rhs_agreement_pneumatic(in.pn.pneumatic_rotary, s, c, Tp / f.substeps, checked);
                   },
                   pneumatic_state_names()});
  for (const HalfCarParams* hp : {&in.bump, &in.iso}) {
    const bool is_bump = hp == &in.bump;
    cases.push_back({is_bump ? "half_car_bump" : "half_car_iso_c",
                     is_bump ? "half car, pitch plane, the paper's double bump at 0.5 s, 20 m/s, passive"
                             : "half car, pitch plane, ISO 8608 class C road at 20 m/s, passive",
                     "z_s", hp->substeps,
                     [&in, hp, T](int n, int reps) { return run_fixed<HalfCarPlant>(*hp, n, in.passive, T, reps); },
                     [&in, hp, T, &stop](double tol) { return reference_half_car(*hp, in.passive, T, tol, stop); },
                     [&in, hp, T](const FixedRun& f, int& checked) {
                       const auto [s, c] = sample_states<HalfCarPlant>(*hp, in.passive, T, 50);
                       return rhs_agreement_half_car(*hp, s, c, T / f.substeps, checked);
                     },
                     half_car_state_names()});
  }
  return cases;
}

// The plant's fixed-step RK4 at 1/4..4x its sub-steps against the
// reference: a JSON entry and a table row each; at the loop's own sub-steps
// also the right-hand side check (into cj).
Json fixed_step_runs(Case& c, const PlantRunSettings& r, const ReferenceResult& ref, std::size_t out_index, Context& ctx,
                     Table& table, Json& cj) {
  Json fixed = Json::array();
  std::vector<int> substeps;
  for (const double m : {0.25, 0.5, 1.0, 2.0, 4.0}) {
    const int n = std::max(1, static_cast<int>(std::lround(c.default_substeps * m)));
    if (std::find(substeps.begin(), substeps.end(), n) == substeps.end()) substeps.push_back(n);
  }
  const double T = r.T;
  for (const int n : substeps) {
    const FixedRun f = c.fixed(n, r.repetitions);
    const ErrorSummary e = compare(f.at, ref.at, c.names);
    Json fj = Json::object();
    fj["substeps"] = n;
    fj["step_us"] = T / n * 1e6;
    fj["wall_s"] = f.wall_s;
    fj["real_time_factor"] = ratio(r.sim_s, f.wall_s);
    fj["speedup_over_reference"] = ratio(ref.stats.wall_s, f.wall_s);
    fj["error"] = error_json(e, c.names);
    if (n == c.default_substeps) {
      int checked = 0;
      const double agreement = c.agreement(f, checked);
      Json a = Json::object();
      a["max_relative_difference"] = agreement;
      a["states_checked"] = checked;
      a["what"] = "one RK4 sub-step by the plant vs by the reference's right-hand side, from the same states";
      cj["rhs_agreement"] = a;
      ctx.out << "  " << c.name << ": reference right-hand side agrees with the plant's to "
              << fmt("%.1e", agreement) << " (" << checked << " states)\n";
    }
    fixed.push_back(fj);
    table.row({c.name, n == c.default_substeps ? "RK4 (loop)" : "RK4", std::to_string(n),
               fmt("%.1f", T / n * 1e6), fmt("%.0f", ratio(r.sim_s, f.wall_s)), c.output,
               fmt("%.3g", e.max_abs[out_index]), fmt("%.3g", e.rms[out_index]),
               fmt("%.2e", e.worst_normalized) + " " + e.worst_component});
  }
  return fixed;
}

// One plant measured: its reference (and, in a full run, how converged that
// is), its fixed-step runs. Empty when the reference was stopped.
std::optional<Json> measure_case(Case& c, const PlantRunSettings& r, Context& ctx, Table& table) {
  Json cj = Json::object();
  cj["description"] = c.description;
  cj["output"] = c.output;
  cj["default_substeps"] = c.default_substeps;
  const std::size_t out_index =
      static_cast<std::size_t>(std::find(c.names.begin(), c.names.end(), c.output) - c.names.begin());

  ReferenceResult ref = c.reference(r.tolerance);
  if (!ref.completed) return std::nullopt;
  cj["reference"] = stats_json(ref.stats, r.sim_s);
  if (!ctx.quick()) {
    // How far the reference itself is from converged: the same at 10x the tolerance.
    const ReferenceResult loose = c.reference(r.tolerance * 10);
    const ErrorSummary self = compare(loose.at, ref.at, c.names);
    Json sj = Json::object();
    sj["tolerance"] = r.tolerance * 10;
    sj["wall_s"] = loose.stats.wall_s;
    sj["difference"] = error_json(self, c.names);
    cj["reference_at_10x_tolerance"] = sj;
  }
  cj["fixed_step"] = fixed_step_runs(c, r, ref, out_index, ctx, table, cj);
  table.row({c.name, "dopri5 " + fmt("%.0e", r.tolerance), "-", fmt("%.2f", ref.stats.wall_s > 0 ? r.sim_s * 1e6 / static_cast<double>(ref.stats.steps) : NAN),
             fmt("%.1f", ratio(r.sim_s, ref.stats.wall_s)), c.output, "(reference)", "", 
             std::to_string(ref.stats.events) + " switches"});
  return cj;
}

Json run_plant_section(Context& ctx) {
  PlantRunSettings r;
  r.sim_s = ctx.pick(20.0, 2.0);
  r.tolerance = ctx.pick(1e-10, 1e-8);
  r.repetitions = ctx.pick(3, 1);
  const PlantInputs inputs(ctx, r.sim_s);
  r.T = inputs.T;
  std::vector<Case> cases = plant_cases(inputs, ctx.stop);

  Json j = Json::object();
  j["simulated_s"] = r.sim_s;
  j["period_s"] = r.T;
  j["reference_tolerance"] = r.tolerance;
  j["timing"] = "wall time of the plant's advance() over every period (best of " + std::to_string(r.repetitions) +
                " runs, one when a run takes over 1 s), single thread; real-time factor = simulated time / wall time";
  j["error"] = "state at every period end against the reference; max_abs_over_range = max |error| / (max - min of the reference)";
  Json out_cases = Json::object();
  ctx.out << "  " << r.sim_s << " s simulated per run, period " << r.T * 1e3 << " ms, reference dopri5 at "
          << r.tolerance << "\n";
  Table table({"plant", "integrator", "substeps", "step us", "real-time x", "output", "max err", "rms err",
               "worst err/range"});
  for (auto& c : cases) {
    if (ctx.stop.load()) break;
    std::optional<Json> cj = measure_case(c, r, ctx, table);
    if (!cj) break;
    out_cases[c.name] = *cj;
  }
  j["cases"] = out_cases;
  ctx.out << table.text();
  return j;
}

}  // namespace

Section plant_section() {
  return {"plant", "plant: speed and accuracy of the fixed-step RK4 against an adaptive reference", run_plant_section};
}

}  // namespace rigctl::bench
