// The diagnosis as rounds (docs/diagnosis.md 4-5): calibrate the baseline
// against its priors; in each round screen every remaining candidate with a
// short refit, refit the best few fully, judge them (criteria.hpp) and add
// the winner; check each kept effect again with the others in; and when
// nothing is named but the baseline misfits beyond the noise, say so.
#include "tools/diagnosis/engine.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "tools/diagnosis/criteria.hpp"
#include "tools/diagnosis/evidence.hpp"
#include "tools/diagnosis/parallel.hpp"
#include "tools/diagnosis/where.hpp"
#include "tools/diagnosis/workspace.hpp"

namespace rigctl::diag {

namespace {

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

struct Candidate {
  std::size_t effect = 0;
  Scored s;
  std::size_t signal = 0;
  double gain = 0.0, se = 0.0;
  double excess_before = 0.0, excess_after = 0.0;  // its signal's held-out rms / noise floor
  double floor = 0.0;                              // the gain it must reach (criteria.hpp gain_floor)
  std::string reason;                              // empty: passes
  std::map<std::string, double> form_costs;        // per form tried (EffectSpec::forms)
};

// ------------------------------------------------------------ tuning
// The engine's numbers, each named once (docs/diagnosis.md 4-5 say why).

// Levenberg-Marquardt iterations of the fits that run to convergence: the
// baseline's calibration (twice, at the nominal and the calibrated prior
// weight) and the backward check; a refit starts from its screening, nearer.
constexpr int kCalibrationIterations = 60;
constexpr int kRefitIterations = 30;
constexpr int kBackwardCheckIterations = 60;
// A strength parameter this many standard deviations from its null is significant.
constexpr double kSignificantSigmas = 3.0;
// The gain's standard error: a block bootstrap of the held-out part, this
// many resamples of kBootstrapBlocks sub-blocks (fixed seed: the verdict does
// not change between runs of the same record).
constexpr int kGainResamples = 200;
constexpr unsigned kGainSeed = 777;
constexpr std::size_t kBootstrapBlocks = 10;
// The confidence: the share of this many resamples the winner wins.
constexpr int kConfidenceResamples = 400;
constexpr unsigned kConfidenceSeed = 12345;
// A candidate with fewer parameters wins a near tie: within this many pp of
// the winner's gain, or this share of it if larger.
constexpr double kNearTiePoints = 0.5;
constexpr double kNearTieShare = 0.1;
// A parameter that stands for a cause ended at its band's edge when it is
// within this share of a tolerance of it.
constexpr double kBandEdgeShare = 0.05;
// Iterations of a candidate's refit in each of its forms: enough to rank
// the forms from the screened start.
constexpr int kFormIterations = 6;

// ------------------------------------------------------------ calibration

// The baseline's MAP fit: the priors' weight is the residual variance per
// effective sample, first of the nominal model, then of the calibrated one
// (a model that misfits badly holds its parameters nearer nominal, so the
// first candidate does not inherit a baseline bent out of shape).
Scored calibrate_baseline(Workspace& w, Diagnosis& d) {
  const Scored nominal = w.score(w.theta_null());
  w.prior_weight = w.residual_variance(nominal);
  const auto free = w.free_for({});
  Scored base = w.fit(nominal.theta, free, kCalibrationIterations, false);
  const int first_iterations = base.iterations;
  w.prior_weight = w.residual_variance(base);
  base = w.fit(base.theta, free, kCalibrationIterations, true);
  w.say("calibrated in " + std::to_string(first_iterations) + " + " + std::to_string(base.iterations) +
        " iterations");
  for (std::size_t i = 0; i < w.n_base; ++i) {
    const auto& sp = w.specs[i];
    Calibrated c{sp.name, sp.unit, sp.init, base.theta[i], base.sigma[i], sp.prior, !base.undetermined[i], false, {},
                 false};
    c.moved = sp.prior > 0.0 && std::abs(c.value - c.nominal) >= 0.5 * sp.prior * std::abs(c.nominal);
    if (!sp.stands_for.empty()) {
      const double edge = sp.toward < 0 ? sp.lo : sp.hi;
      c.stands_for = sp.stands_for;
      c.at_band_edge = std::abs(c.value - edge) <= kBandEdgeShare * sp.prior * std::abs(c.nominal);
    }
    c.timing = sp.timing;
    c.lo = sp.lo;
    c.hi = sp.hi;
    d.calibration.push_back(c);
    d.baseline_parameters.push_back({sp.name, sp.unit, c.value, c.sigma, c.determined});
  }
  return base;
}

// ------------------------------------------------------------ one round

std::vector<std::vector<double>> starts_of(const Workspace& w, std::size_t e, const std::vector<double>& from) {
  const auto& params = w.effects[e].params;
  std::vector<double> st = from;
  for (std::size_t j = 0; j < params.size(); ++j) st[w.offset[e] + j] = params[j].init;
  std::vector<std::vector<double>> starts{st};
  for (std::size_t j = 0; j < params.size(); ++j)
    for (double v : params[j].starts) {
      auto s2 = st;
      s2[w.offset[e] + j] = v;
      starts.push_back(s2);
    }
  return starts;
}

// Levenberg-Marquardt iterations of a screening fit. Screening only ranks
// the candidates for the full refit (which runs to convergence): from the
// calibrated baseline the first two or three steps take most of a real
// effect's cost reduction. 3 instead of 5 cut the quarter car's screening
// (nine candidates, up to 14 free parameters, per round) by about 40 %.
constexpr int kScreeningIterations = 3;

// The free parameters of a fit with these effects in: their own, and the
// baseline parameters that can change the outputs they act on (a rig of
// sub-models does not replay the others' parameters; RigModel::couples).
std::vector<bool> coupled_free(const Workspace& w, const std::vector<std::size_t>& effects) {
  std::vector<bool> free = w.free_for(effects);
  for (std::size_t i = 0; i < w.n_base; ++i) {
    bool any = false;
    for (auto e : effects) any = any || w.model.couples(i, w.effects[e].cause);
    free[i] = any;
  }
  return free;
}

// A full fit with these effects in, the coupled baseline parameters free;
// the baseline parameters held keep the standard deviations (and the
// determined flags) of `from`, the fit they were last free in.
Scored fit_coupled(const Workspace& w, const std::vector<double>& start, const std::vector<std::size_t>& effects,
                   int iterations, const Scored& from) {
  const auto free = coupled_free(w, effects);
  Scored s = w.fit(start, free, iterations, true);
  for (std::size_t i = 0; i < w.n_base; ++i)
    if (!free[i] && i < from.sigma.size()) {
      s.sigma[i] = from.sigma[i];
      s.undetermined[i] = from.undetermined[i];
    }
  return s;
}

// After an effect is accepted: the priors' weight becomes the residual
// variance of the model with it, and that model is refitted at the new
// weight. A large misfit (a strong friction nobody modelled yet) weighs the
// priors heavily and holds the uncertain parameters near nominal; once the
// friction is in, a rig 4 % short of the nominal flow gain must be
// calibrated as such, not leave the 4 % to the next candidate with a free
// scale (a gas exponent, docs/diagnosis.md 4).
constexpr int kRecalibrationIterations = 30;
// Only when the accepted effect took at least half the residual variance
// away: a small one (a seal beside a body still misfit) leaves the weight
// nearly where it was, and refitting every parameter buys nothing but time
// (the quarter car's bearing + seal pair: 38 s instead of 45 s).
constexpr double kRecalibrationDrop = 0.5;
Scored recalibrate(Workspace& w, const Scored& current, const std::vector<std::size_t>& active) {
  const double weight = w.residual_variance(current);
  if (!(weight < kRecalibrationDrop * w.prior_weight)) return current;
  w.prior_weight = weight;
  w.say("recalibrating with " + std::to_string(active.size()) + " effect(s) in");
  Scored s = fit_coupled(w, current.theta, active, kRecalibrationIterations, current);
  w.say("  recalibrated in " + std::to_string(s.iterations) + " iterations");
  return s;
}

// Screening: a short refit per start of the effect's grid, the baseline's
// parameters free too (they may have bent to mimic the missing effect),
// effects already kept held where the current fit put them. Best first.
// The candidates are independent: they are screened side by side on the
// workers (parallel.hpp), which keeps both cores busy through the parts of
// a fit that are not its Jacobian.
std::vector<Candidate> screen(const Workspace& w, const Scored& current, const std::vector<std::size_t>& active,
                              int round) {
  std::vector<std::size_t> todo;
  for (std::size_t e = 0; e < w.effects.size(); ++e)
    if (!w.effects[e].stub && std::find(active.begin(), active.end(), e) == active.end()) todo.push_back(e);
  std::vector<Candidate> out(todo.size());
  parallel_for(w.threads, todo.size(), [&](std::size_t k, std::size_t) {
    const std::size_t e = todo[k];
    w.say("round " + std::to_string(round) + ": screening " + w.effects[e].cause);
    std::vector<bool> free = coupled_free(w, {e});
    Candidate& best = out[k];
    best.effect = e;
    best.s.est_sse = std::numeric_limits<double>::infinity();
    for (const auto& s : starts_of(w, e, current.theta)) {
      auto r = w.fit(s, free, kScreeningIterations, false);
      if (r.est_sse < best.s.est_sse) best.s = std::move(r);
    }
  });
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) { return a.s.est_sse < b.s.est_sse; });
  return out;
}

// Held-out residual rms of output o over the record's noise floor on it.
double held_out_excess(const Workspace& w, const Scored& s, std::size_t o) {
  return w.noise[o] > 0.0 ? w.held_out_rms(s, o) / w.noise[o] : 0.0;
}

// What the gates need of output o beyond the gain: the misfit of the model
// `without` an effect and of the one `with` it (criteria.hpp gain_floor).
CandidateEvidence misfit_evidence(const Workspace& w, const Scored& without, const Scored& with, std::size_t o) {
  CandidateEvidence ev;
  ev.gain = with.fit[o] - without.fit[o];
  ev.excess_before = held_out_excess(w, without, o);
  ev.excess_after = held_out_excess(w, with, o);
  ev.fit_before = without.fit[o];
  return ev;
}

bool strength_significant(const Workspace& w, std::size_t e, const Scored& s) {
  for (std::size_t j = 0; j < w.effects[e].params.size(); ++j) {
    const auto& ps = w.effects[e].params[j];
    const double val = s.theta[w.offset[e] + j], sg = s.sigma[w.offset[e] + j];
    if (ps.strength && std::isfinite(sg) && std::abs(val - ps.null) >= kSignificantSigmas * sg) return true;
  }
  return false;
}

// A candidate of several forms (EffectSpec::forms): its parameters and the
// baseline's it couples to refitted briefly in each form from `start`, the
// form with the lowest estimation cost returned as a start for its refit
// (`start` itself where that is the form it has). Its own parameters alone were not
// enough: the screened baseline had bent to the first form (a Bessel filter
// was taken for one of order 3). One form: the start unchanged.
std::vector<double> best_form(const Workspace& w, std::size_t e, std::vector<double> start,
                              std::map<std::string, double>& costs) {
  const auto& eff = w.effects[e];
  std::size_t form = eff.params.size();
  for (std::size_t j = 0; j < eff.params.size(); ++j)
    if (eff.params[j].form) form = j;
  if (form == eff.params.size() || eff.forms.size() < 2) return start;
  const std::vector<bool> own = coupled_free(w, {e});
  std::vector<Scored> fits(eff.forms.size());
  parallel_for(w.threads, fits.size(), [&](std::size_t f, std::size_t) {
    auto s = start;
    s[w.offset[e] + form] = static_cast<double>(f);
    fits[f] = w.fit(s, own, kFormIterations, false);
  });
  std::size_t best = 0;
  for (std::size_t f = 0; f < fits.size(); ++f) {
    costs[eff.forms[f]] = fits[f].est_sse;
    if (fits[f].est_sse < fits[best].est_sse) best = f;
  }
  w.say("  " + eff.cause + ": form " + eff.forms[best] + " fits best");
  if (static_cast<double>(best) == start[w.offset[e] + form]) return start;  // the form it has
  return fits[best].theta;
}

// Full refit of one screened candidate, judged against the current model
// (every candidate of the round at the same N_eff, neff).
// Judges the refitted candidate r (r.effect and r.s set) against the current
// model: its signal, gain and standard error, and the gates' verdict.
void judge(const Workspace& w, Candidate& r, const Scored& current, const std::vector<std::size_t>& active,
           double neff) {
  const std::string& cause = w.effects[r.effect].cause;
  auto act = active;
  act.push_back(r.effect);
  // Its signal: the largest gain among the outputs where it reaches its
  // floor (a delay may gain most on dp but explain the misfit of theta),
  // else the largest gain.
  CandidateEvidence ev;
  ev.gain = -1e9;
  bool reaches = false;
  for (std::size_t o = 0; o < w.outs().size(); ++o) {
    const CandidateEvidence here = misfit_evidence(w, current, r.s, o);
    const bool passes = here.gain >= gain_floor(here, w.options);
    if ((passes && !reaches) || (passes == reaches && here.gain > ev.gain)) ev = here, r.signal = o, reaches = passes;
  }
  const auto& sig = r.signal;
  r.gain = ev.gain;
  const auto fits = bootstrap_fits(w.outs()[sig].measured, {&current.y[sig], &r.s.y[sig]}, w.val_begin, w.n,
                                   kGainResamples, kGainSeed, kBootstrapBlocks,
                                   activity_strata(current.y[sig], r.s.y[sig], w.val_begin, w.n, kBootstrapBlocks));
  r.se = ev.se = gain_standard_error(fits, 1, 0);
  // Parsimony on the outputs the candidate acts on (RigModel::acts_on): a
  // sub-model's effect is not judged against the other sub-model's misfit
  // (a seal friction's 1.5 pp on p1 was lost in the body's misfit after
  // bearing friction, strongly coloured and many times larger).
  const auto on = w.model.acts_on(cause);
  const auto cur = w.on_outputs(current, on), cand = w.on_outputs(r.s, on);
  const double n_eff = on.empty() ? neff : cur.n_eff;
  ev.significant = strength_significant(w, r.effect, r.s);
  ev.bic_new = bic(cand.sse, w.parameter_count(act), n_eff, cand.values);
  ev.bic_current = bic(cur.sse, w.parameter_count(active), n_eff, cur.values);
  r.reason = rejection(ev, w.options);
  r.excess_before = ev.excess_before;
  r.excess_after = ev.excess_after;
  r.floor = gain_floor(ev, w.options);
}

// Full refit of one screened candidate, judged against the current model
// (every candidate of the round at the same N_eff, neff). A candidate of
// several forms is refitted in its first form; only where that reaches its
// gain floor are its forms ranked (best_form) and, where another fits
// better, refitted in that one and judged again: the forms are what the
// JSON reports of a named cause, and ranking them for every candidate that
// is then rejected doubled a quarter-car round.
Candidate refit_one(const Workspace& w, const Candidate& screened, const Scored& current,
                    const std::vector<std::size_t>& active, double neff, int round) {
  Candidate r;
  r.effect = screened.effect;
  const std::string& cause = w.effects[r.effect].cause;
  w.say("round " + std::to_string(round) + ": refitting " + cause);
  auto act = active;
  act.push_back(r.effect);
  // The baseline parameters the kept and the new effects couple to are
  // free; the others stay where the calibration put them (their
  // sub-model's outputs do not change with the candidate).
  r.s = fit_coupled(w, screened.s.theta, act, kRefitIterations, current);
  w.say("  " + cause + ": refitted in " + std::to_string(r.s.iterations) + " iterations");
  judge(w, r, current, active, neff);
  if (w.effects[r.effect].forms.size() < 2 || r.gain < r.floor) return r;
  const auto start = best_form(w, r.effect, r.s.theta, r.form_costs);
  if (start == r.s.theta) return r;
  Candidate other = r;
  other.s = fit_coupled(w, start, act, kRefitIterations, current);
  if (!(other.s.est_sse < r.s.est_sse)) return r;
  judge(w, other, current, active, neff);
  return other;
}

// Full refit of the best few, side by side on the workers (they are
// independent), each judged against the current model; the screening
// record in screening order.
std::vector<Candidate> refit_best(const Workspace& w, std::vector<Candidate> screened, const Scored& current,
                                  const std::vector<std::size_t>& active, int round, Diagnosis& d,
                                  std::size_t extra = 0) {
  const double neff = w.n_eff(current);  // every candidate of the round is compared at this one
  const std::size_t top =
      std::min(screened.size(), static_cast<std::size_t>(std::max(0, w.options.refit_top)) + extra);
  std::vector<Candidate> refits(top);
  parallel_for(w.threads, top, [&](std::size_t c, std::size_t) { refits[c] = refit_one(w, screened[c], current, active, neff, round); });
  for (std::size_t c = 0; c < screened.size(); ++c) {
    ScreenedCandidate sc;
    sc.cause = w.effects[screened[c].effect].cause;
    sc.round = round;
    sc.estimation_cost = screened[c].s.est_sse;
    if (c >= top) {
      sc.reason = "not among the best " + std::to_string(w.options.refit_top) + " in screening";
    } else {
      const Candidate& r = refits[c];
      sc.refitted = true;
      sc.gain_percent_points = r.gain;
      sc.signal = w.outs()[r.signal].name;
      sc.reason = r.reason.empty() ? "passes" : r.reason;
      std::string misfit;
      if (r.floor < w.options.min_gain)
        misfit = "; residual " + fmt(r.excess_before, 3) + " -> " + fmt(r.excess_after, 3) + " x its noise floor";
      w.say("  " + sc.cause + ": gain " + fmt(r.gain, 3) + " pp on " + sc.signal + " (" + sc.reason + misfit + ")");
    }
    d.screened.push_back(sc);
  }
  return refits;
}

// Where before what: the best-screened candidate entering where the misfit
// is is refitted too when none of the best few does (where.hpp).
std::size_t promote_where(const Workspace& w, const WhereResult& where, std::vector<Candidate>& screened) {
  std::vector<std::string> causes;
  for (const auto& c : screened) causes.push_back(w.effects[c.effect].cause);
  const auto top = static_cast<std::size_t>(std::max(0, w.options.refit_top));
  const std::size_t k = where_promotion(where, causes, top);
  if (k >= screened.size()) return 0;
  w.say("where: refitting " + causes[k] + " too (it enters where the misfit is)");
  std::rotate(screened.begin() + static_cast<std::ptrdiff_t>(top), screened.begin() + static_cast<std::ptrdiff_t>(k),
              screened.begin() + static_cast<std::ptrdiff_t>(k + 1));
  return 1;
}

// The largest passing gain wins; one with fewer parameters wins a near tie.
const Candidate* choose(const Workspace& w, const std::vector<Candidate>& refits) {
  const Candidate* win = nullptr;
  for (const auto& r : refits)
    if (r.reason.empty() && (!win || r.gain > win->gain)) win = &r;
  if (!win) return nullptr;
  const double margin = std::max(kNearTiePoints, kNearTieShare * win->gain);
  for (const auto& r : refits)
    if (r.reason.empty() && r.gain >= win->gain - margin &&
        w.effects[r.effect].params.size() < w.effects[win->effect].params.size())
      win = &r;
  return win;
}

// Confidence: the share of block-bootstrap resamples of the held-out part
// in which the winner has the largest gain, and at least its floor (g_min,
// or explained_min_gain when it explains a misfit beyond the noise).
double confidence(const Workspace& w, const Candidate& win, const std::vector<Candidate>& refits,
                  const Scored& current) {
  std::vector<const std::vector<double>*> sims{&current.y[win.signal]};
  std::size_t wi = 0;
  for (std::size_t r = 0; r < refits.size(); ++r) {
    if (&refits[r] == &win) wi = r + 1;
    sims.push_back(&refits[r].s.y[win.signal]);
  }
  const auto fits = bootstrap_fits(w.outs()[win.signal].measured, sims, w.val_begin, w.n, kConfidenceResamples,
                                   kConfidenceSeed, kBootstrapBlocks);
  int wins = 0;
  for (const auto& row : fits) {
    std::size_t best = 1;
    for (std::size_t s = 2; s < row.size(); ++s)
      if (row[s] > row[best]) best = s;
    if (best == wi && row[best] - row[0] >= win.floor) ++wins;
  }
  return static_cast<double>(wins) / static_cast<double>(fits.size());
}

// The sensor channels an effect's parameters showed: those more than
// kSignificantSigmas from their null and at least kChannelShareOfLargest of
// the largest departure; none such, the largest departure's.
// Why the share: a sensor's delay a twentieth of the late channels' (0.33 ms
// on x_r beside 6 ms on x_b and x_w, 3.3 sigma, in the project's own
// quarter-car run with the feedback untouched) is the replay's timing
// residue, not a late transducer; a fifth keeps every channel of a filter on
// several sensors alike (the development set's Bessel on x_r, x_w and x_b).
constexpr double kChannelShareOfLargest = 0.2;

std::vector<std::string> showed_channels(const Workspace& w, std::size_t e, const Scored& s) {
  std::vector<std::string> out;
  const auto& params = w.effects[e].params;
  std::string largest;
  double most = 0.0;
  for (std::size_t j = 0; j < params.size(); ++j) {
    if (params[j].channel.empty()) continue;
    const double dep = std::abs(s.theta[w.offset[e] + j] - params[j].null);
    if (dep > most) most = dep, largest = params[j].channel;
  }
  for (std::size_t j = 0; j < params.size(); ++j) {
    if (params[j].channel.empty()) continue;
    const std::size_t i = w.offset[e] + j;
    const double dep = std::abs(s.theta[i] - params[j].null);
    if (std::isfinite(s.sigma[i]) && dep >= kSignificantSigmas * s.sigma[i] && dep > 0.0 &&
        dep >= kChannelShareOfLargest * most)
      out.push_back(params[j].channel);
  }
  if (out.empty() && !largest.empty()) out.push_back(largest);
  return out;
}

CauseResult describe(const Workspace& w, const Candidate& win, const std::vector<Candidate>& refits,
                     const Scored& current, Diagnosis& d) {
  const auto& eff = w.effects[win.effect];
  CauseResult cr;
  cr.cause = eff.cause;
  cr.confidence = confidence(w, win, refits, current);
  cr.signal = w.outs()[win.signal].name;
  cr.baseline_fit_percent = current.fit[win.signal];
  cr.extended_fit_percent = win.s.fit[win.signal];
  cr.gain_percent_points = win.gain;
  for (const auto& r : refits)
    if (&r != &win && r.gain >= r.floor && about_equal(r.gain, win.gain, w.options))
      cr.ambiguous_with.push_back(w.effects[r.effect].cause);
  for (std::size_t j = 0; j < eff.params.size(); ++j) {
    const std::size_t i = w.offset[win.effect] + j;
    if (eff.params[j].form) {
      cr.form = eff.forms.empty() ? "" : eff.forms[static_cast<std::size_t>(std::clamp<long>(
                                             std::lround(win.s.theta[i]), 0, static_cast<long>(eff.forms.size()) - 1))];
      continue;
    }
    cr.parameters.push_back({eff.params[j].name, eff.params[j].unit, win.s.theta[i], win.s.sigma[i],
                             !win.s.undetermined[i], eff.params[j].channel});
  }
  cr.form_costs = win.form_costs;
  cr.channels = showed_channels(w, win.effect, win.s);
  const auto ind = w.model.indicator(cr.cause);
  const auto before = w.residual(current, win.signal);
  const double dt = w.n > 1 ? (w.model.time().back() - w.model.time().front()) / static_cast<double>(w.n - 1) : 1.0;
  cr.signature = signature(cr.cause, ind.name, ind.values, before, w.outs()[win.signal].measured,
                           current.y[win.signal], dt, w.val_begin, w.n);
  std::ostringstream ev;
  ev << eff.description << ". Held-out fit of " << cr.signal << " " << fmt(cr.baseline_fit_percent) << " % -> "
     << fmt(cr.extended_fit_percent) << " % (free-run replay, +-" << fmt(win.se, 2) << " pp bootstrap)";
  for (const auto& pv : cr.parameters)
    ev << "; " << pv.name << " = " << (pv.determined ? fmt(pv.value) + " +- " + fmt(pv.sigma, 2) : "undetermined")
       << " " << pv.unit;
  if (!ind.name.empty()) {
    const double r2a = binned_r2(ind.values, before, w.val_begin, w.n);
    const double r2b = binned_r2(ind.values, w.residual(win.s, win.signal), w.val_begin, w.n);
    ev << "; residual of " << cr.signal << " explained by " << ind.name << " (binned): R2 " << fmt(r2a, 2)
       << " before, " << fmt(r2b, 2) << " after";
    d.cause_plots.push_back({cr.cause, ind.name, cr.signal, ind.values, before, w.model.effect_term(cr.cause, win.s.theta)});
  }
  for (const auto& c : d.calibration)
    if (c.at_band_edge && c.stands_for == cr.cause)
      ev << "; the calibration held the baseline's " << c.name << " at the edge of its band ("
         << fmt(100.0 * (c.value - c.nominal) / c.nominal, 3) << " %, " << fmt(kCauseBandTolerances, 2)
         << " tolerances): the run asked for more, which is this cause";
  if (!cr.signature.empty()) ev << "; signature: " << cr.signature;
  cr.where_agrees = where_agrees(d.where, cr.cause);
  if (!cr.where_agrees)
    ev << "; its place disagrees with where the baseline's misfit is (" << d.where.sentence << ")";
  if (!cr.ambiguous_with.empty()) {
    ev << "; about as well explained by";
    for (const auto& a : cr.ambiguous_with) ev << " " << a;
  }
  ev << "; beat the other refitted candidates in " << fmt(100.0 * cr.confidence, 3)
     << " % of block-bootstrap resamples of the held-out part";
  cr.evidence = ev.str();
  return cr;
}

// ------------------------------------------------------------ after the rounds

// Every kept effect must still earn its floor with the others in.
void backward_check(const Workspace& w, std::vector<std::size_t>& active, Scored& current, Diagnosis& d) {
  if (active.size() < 2) return;
  for (std::size_t k = 0; k < active.size();) {
    std::vector<std::size_t> others;
    for (std::size_t j = 0; j < active.size(); ++j)
      if (j != k) others.push_back(active[j]);
    auto start = current.theta;
    const auto& eff = w.effects[active[k]];
    for (std::size_t j = 0; j < eff.params.size(); ++j) start[w.offset[active[k]] + j] = eff.params[j].null;
    w.say("backward check: without " + eff.cause);
    const Scored without = fit_coupled(w, start, others, kBackwardCheckIterations, current);
    double best = -1e9;
    bool earns = false;
    for (std::size_t o = 0; o < w.outs().size(); ++o) {
      best = std::max(best, current.fit[o] - without.fit[o]);
      const CandidateEvidence ev = misfit_evidence(w, without, current, o);
      earns = earns || ev.gain >= gain_floor(ev, w.options);
    }
    if (!earns) {
      w.say("  dropped " + eff.cause + " (only " + fmt(best, 3) + " pp given the others)");
      d.causes.erase(std::remove_if(d.causes.begin(), d.causes.end(), [&](auto& r) { return r.cause == eff.cause; }),
                     d.causes.end());
      active.erase(active.begin() + static_cast<std::ptrdiff_t>(k));
      current = without;
    } else {
      ++k;
    }
  }
}

// No cause, but a channel that misfits beyond its noise
// (criteria.hpp misfits_beyond_noise): the model is wrong in a way nobody
// named.
void check_unexplained(const Workspace& w, const Scored& current, Diagnosis& d) {
  if (!d.causes.empty()) return;
  const double dt = w.n > 1 ? (w.model.time().back() - w.model.time().front()) / static_cast<double>(w.n - 1) : 1.0;
  double worst = 0.0;
  for (std::size_t o = 0; o < w.outs().size(); ++o) {
    const double excess = held_out_excess(w, current, o);
    if (misfits_beyond_noise(excess, current.fit[o]) && excess > worst) {
      worst = excess;
      const Band band = power_band(w.residual(current, o), dt, w.val_begin, w.n);
      d.unexplained = true;
      d.unexplained_residual = {w.outs()[o].name, w.held_out_rms(current, o), w.noise[o], band.lo_hz, band.hi_hz,
                                band.peak_hz};
    }
  }
  if (d.unexplained)
    w.say("unexplained: " + d.unexplained_residual.signal + " misfits " + fmt(worst, 3) + " x its noise floor, " +
          fmt(d.unexplained_residual.band_lo_hz, 3) + "-" + fmt(d.unexplained_residual.band_hi_hz, 3) + " Hz");
}

void finish(const Workspace& w, const std::vector<std::size_t>& active, const Scored& base, const Scored& current,
            Diagnosis& d) {
  d.cause = d.causes.empty() ? "none" : d.causes.front().cause;
  d.model_constants = w.model.constants();
  const auto fr = w.free_for(active);
  for (std::size_t i = 0; i < w.specs.size(); ++i)
    if (fr[i])
      d.final_parameters.push_back({w.specs[i].name, w.specs[i].unit, current.theta[i],
                                    current.sigma.empty() ? 0.0 : current.sigma[i],
                                    current.undetermined.empty() || !current.undetermined[i]});
  // Each named cause reports its parameters from the final joint fit: the
  // round that accepted it ran without the effects added later.
  for (auto& cr : d.causes)
    for (auto e : active) {
      if (w.effects[e].cause != cr.cause) continue;
      const auto& params = w.effects[e].params;
      for (auto& pv : cr.parameters)
        for (std::size_t j = 0; j < params.size(); ++j) {
          if (params[j].name != pv.name) continue;
          const std::size_t i = w.offset[e] + j;
          pv.value = current.theta[i];
          if (!current.sigma.empty()) pv.sigma = current.sigma[i];
          if (!current.undetermined.empty()) pv.determined = !current.undetermined[i];
        }
      if (!current.sigma.empty()) cr.channels = showed_channels(w, e, current);
    }
  for (std::size_t o = 0; o < w.outs().size(); ++o) {
    d.baseline_fit_percent[w.outs()[o].name] = base.fit[o];
    d.extended_fit_percent[w.outs()[o].name] = current.fit[o];
  }
  std::size_t moved = 0;
  for (const auto& c : d.calibration) moved += c.moved ? 1 : 0;
  std::ostringstream v;
  v << "contiguous split: the first " << fmt(100.0 * (1.0 - w.options.holdout_fraction), 3) << " % of the record ("
    << w.n_est << " of " << w.n << " samples, after a " << w.init
    << "-sample initialisation window) for fitting, the last " << fmt(100.0 * w.options.holdout_fraction, 3)
    << " % held out; fits above are free-run simulations of the whole record with the fitted parameters, scored "
       "on the held-out samples only; the baseline is calibrated first (its uncertain parameters free, each "
       "regularised toward nominal by a prior of its stated tolerance; "
    << moved << " moved by half their tolerance or more); " << w.model.replay();
  d.validation = v.str();
  d.t = w.model.time();
  d.validation_start = w.val_begin;
  for (std::size_t o = 0; o < w.outs().size(); ++o) {
    d.output_names.push_back(w.outs()[o].name);
    d.measured.push_back(w.outs()[o].measured);
    d.y_baseline.push_back(base.y[o]);
    d.y_extended.push_back(current.y[o]);
  }
}

}  // namespace

Diagnosis diagnose(const RigModel& model, const DiagnoseOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  Workspace w(model, opt);
  Diagnosis d;
  d.rig = to_string(model.rig());
  for (const auto& e : w.effects)
    if (e.stub) d.stubs.push_back(e.cause);

  w.say("baseline calibration (" + std::to_string(w.n_base) + " parameters, " + std::to_string(w.n) + " samples)");
  const Scored base = calibrate_baseline(w, d);
  d.where = locate(w, base);
  if (d.where.computed) w.say("where: " + d.where.sentence);
  {
    std::string s = "baseline held-out fit:";
    for (std::size_t o = 0; o < w.outs().size(); ++o) s += " " + w.outs()[o].name + " " + fmt(base.fit[o]) + " %";
    w.say(s);
  }
  Scored current = base;
  std::vector<std::size_t> active;
  for (int round = 1; round <= (opt.calibration_only ? 0 : opt.max_effects); ++round) {
    auto screened = screen(w, current, active, round);
    if (screened.empty()) break;
    const std::size_t promoted = round == 1 ? promote_where(w, d.where, screened) : 0;
    const auto refits = refit_best(w, std::move(screened), current, active, round, d, promoted);
    const Candidate* win = choose(w, refits);
    if (!win) break;
    for (auto& sc : d.screened)
      if (sc.round == round && sc.cause == w.effects[win->effect].cause) sc.accepted = true;
    d.causes.push_back(describe(w, *win, refits, current, d));
    w.say("accepted " + d.causes.back().cause + " (gain " + fmt(win->gain, 3) + " pp on " + d.causes.back().signal + ")");
    active.push_back(win->effect);
    current = recalibrate(w, win->s, active);  // a rejected candidate stays in the pool: it may pass later
  }
  if (!opt.calibration_only) {
    backward_check(w, active, current, d);
    check_unexplained(w, current, d);
  }
  finish(w, active, base, current, d);
  d.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  w.say("done: cause " + d.cause);
  return d;
}

}  // namespace rigctl::diag
