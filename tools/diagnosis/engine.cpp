#include "tools/diagnosis/engine.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>

#include "tools/diagnosis/fit.hpp"

namespace rigctl::diag {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Layout {
  std::vector<ParamSpec> specs;
  std::vector<std::size_t> offset;  // of each effect's first parameter
  std::size_t n_base = 0;
};

Layout layout_of(const RigModel& model, const std::vector<EffectSpec>& effects) {
  Layout l;
  l.specs = model.baseline();
  l.n_base = l.specs.size();
  for (const auto& e : effects) {
    l.offset.push_back(l.specs.size());
    for (const auto& p : e.params) l.specs.push_back(p);
  }
  return l;
}

struct Scored {
  std::vector<double> theta;
  std::vector<double> sigma;
  std::vector<std::vector<double>> y;
  std::vector<double> fit;  // per output, held-out
  double est_sse = 0.0;
  bool rank_deficient = false;
};

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

// Share of the residual's variance explained by its mean in quantile bins of
// the indicator (conditional statistics, docs/diagnosis.md 3).
double binned_r2(const std::vector<double>& ind, const std::vector<double>& e, std::size_t b, std::size_t end) {
  if (ind.size() < end || end <= b + 20) return 0.0;
  std::vector<std::size_t> idx(end - b);
  std::iota(idx.begin(), idx.end(), b);
  std::sort(idx.begin(), idx.end(), [&](auto i, auto j) { return ind[i] < ind[j]; });
  const std::size_t bins = 20, n = idx.size();
  double mean = 0.0;
  for (auto i : idx) mean += e[i];
  mean /= static_cast<double>(n);
  double tot = 0.0, expl = 0.0;
  for (auto i : idx) tot += (e[i] - mean) * (e[i] - mean);
  for (std::size_t k = 0; k < bins; ++k) {
    const std::size_t lo = k * n / bins, hi = (k + 1) * n / bins;
    if (hi <= lo) continue;
    double m = 0.0;
    for (std::size_t j = lo; j < hi; ++j) m += e[idx[j]];
    m /= static_cast<double>(hi - lo);
    expl += static_cast<double>(hi - lo) * (m - mean) * (m - mean);
  }
  return tot > 0.0 ? expl / tot : 0.0;
}

}  // namespace

double fit_percent(const std::vector<double>& y, const std::vector<double>& y_sim, std::size_t begin, std::size_t end) {
  end = std::min({end, y.size(), y_sim.size()});
  if (end <= begin) return 0.0;
  double mean = 0.0;
  for (std::size_t i = begin; i < end; ++i) mean += y[i];
  mean /= static_cast<double>(end - begin);
  double num = 0.0, den = 0.0;
  for (std::size_t i = begin; i < end; ++i) {
    num += (y[i] - y_sim[i]) * (y[i] - y_sim[i]);
    den += (y[i] - mean) * (y[i] - mean);
  }
  if (den <= 0.0) return 0.0;
  return 100.0 * (1.0 - std::sqrt(num / den));
}

Diagnosis diagnose(const RigModel& model, const DiagnoseOptions& opt) {
  const auto t0 = Clock::now();
  auto say = [&](const std::string& s) {
    if (opt.progress) *opt.progress << "diagnose [" << std::fixed << std::setprecision(1) << seconds_since(t0)
                                    << std::defaultfloat << " s] " << s << std::endl;
  };
  Diagnosis d;
  d.rig = to_string(model.rig());
  const auto effects = model.effects();
  const Layout L = layout_of(model, effects);
  const auto& outs = model.outputs();
  const std::size_t n = model.time().size();
  const std::size_t init = std::min(model.init_window(), n / 10);
  const std::size_t n_est = static_cast<std::size_t>(std::floor(static_cast<double>(n) * (1.0 - opt.holdout_fraction)));
  const std::size_t val_begin = std::max(n_est, init);
  std::vector<unsigned char> est_mask(n, 0);
  for (std::size_t i = init; i < n_est; ++i) est_mask[i] = 1;
  std::vector<double> weight;
  for (const auto& o : outs) {
    double m = 0.0, s = 0.0;
    for (double v : o.measured) m += v;
    m /= static_cast<double>(n);
    for (double v : o.measured) s += (v - m) * (v - m);
    s = std::sqrt(s / static_cast<double>(n));
    weight.push_back(s > 0.0 ? 1.0 / s : 1.0);
  }
  for (const auto& e : effects)
    if (e.stub) d.stubs.push_back(e.cause);

  std::vector<double> theta_null(L.specs.size());
  for (std::size_t i = 0; i < L.specs.size(); ++i) theta_null[i] = i < L.n_base ? L.specs[i].init : L.specs[i].null;

  auto score = [&](const std::vector<double>& theta) {
    Scored s;
    s.theta = theta;
    model.simulate(theta, s.y);
    for (std::size_t o = 0; o < outs.size(); ++o) s.fit.push_back(fit_percent(outs[o].measured, s.y[o], val_begin, n));
    return s;
  };
  auto fit = [&](const std::vector<double>& start, const std::vector<bool>& free, int iters, bool cov) {
    FitProblem p;
    p.model = &model;
    p.specs = L.specs;
    p.free = free;
    p.theta0 = start;
    p.mask = est_mask;
    p.weight = weight;
    p.max_iterations = iters;
    const auto r = fit_output_error(p, cov);
    Scored s = score(r.theta);
    s.sigma = r.sigma;
    s.est_sse = 2.0 * r.cost;
    s.rank_deficient = r.rank_deficient;
    return s;
  };
  auto free_for = [&](const std::vector<std::size_t>& active) {
    std::vector<bool> f(L.specs.size(), false);
    for (std::size_t i = 0; i < L.n_base; ++i) f[i] = true;
    for (auto e : active)
      for (std::size_t j = 0; j < effects[e].params.size(); ++j) f[L.offset[e] + j] = true;
    return f;
  };
  std::size_t n_free_est = 0;
  for (auto m : est_mask) n_free_est += m;
  n_free_est *= outs.size();
  auto residual_of = [&](const Scored& s, std::size_t o) {
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i) r[i] = outs[o].measured[i] - s.y[o][i];
    return r;
  };
  // N_eff of a model's residual (its colour); two models are compared with
  // the same N_eff (the current model's), or a candidate whose residual is
  // more coloured would be judged on fewer samples and lose for that alone.
  auto n_eff = [&](const Scored& s) {
    std::vector<double> r;
    const auto e = residual_of(s, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (est_mask[i]) r.push_back(e[i] * weight[0]);
    return std::max(10.0, static_cast<double>(n_free_est) * effective_fraction(r));
  };
  auto bic = [&](const Scored& s, std::size_t k, double neff) {
    return neff * std::log(std::max(s.est_sse, 1e-300) / static_cast<double>(n_free_est)) +
           static_cast<double>(k) * std::log(neff);
  };

  say("baseline fit (" + std::to_string(L.n_base) + " parameters, " + std::to_string(n) + " samples)");
  Scored current = fit(theta_null, free_for({}), 100, true);
  const Scored base = current;
  for (std::size_t i = 0; i < L.n_base; ++i)
    d.baseline_parameters.push_back({L.specs[i].name, L.specs[i].unit, base.theta[i], base.sigma[i]});
  {
    std::string s = "baseline held-out fit:";
    for (std::size_t o = 0; o < outs.size(); ++o) s += " " + outs[o].name + " " + fmt(base.fit[o]) + " %";
    say(s);
  }
  std::vector<std::size_t> active;
  std::vector<bool> tried(effects.size(), false);
  for (std::size_t e = 0; e < effects.size(); ++e) tried[e] = effects[e].stub;

  for (int round = 1; round <= opt.max_effects; ++round) {
    // Screening: short refits from each start of the effect's grid.
    struct Cand {
      std::size_t e;
      Scored s;
    };
    std::vector<Cand> cands;
    for (std::size_t e = 0; e < effects.size(); ++e) {
      if (tried[e] || std::find(active.begin(), active.end(), e) != active.end()) continue;
      say("round " + std::to_string(round) + ": screening " + effects[e].cause);
      // Screening frees the candidate's parameters and the baseline's (the
      // baseline fit has bent its parameters to mimic the missing effect, so
      // they must be able to move back); effects already kept stay where the
      // current fit put them. The best few are then refitted with all free.
      std::vector<bool> free = free_for({});
      for (std::size_t j = 0; j < effects[e].params.size(); ++j) free[L.offset[e] + j] = true;
      std::vector<std::vector<double>> starts;
      std::vector<double> st = current.theta;
      for (std::size_t j = 0; j < effects[e].params.size(); ++j) st[L.offset[e] + j] = effects[e].params[j].init;
      starts.push_back(st);
      for (std::size_t j = 0; j < effects[e].params.size(); ++j)
        for (double v : effects[e].params[j].starts) {
          auto s2 = st;
          s2[L.offset[e] + j] = v;
          starts.push_back(s2);
        }
      Scored best;
      best.est_sse = std::numeric_limits<double>::infinity();
      for (const auto& s : starts) {
        auto r = fit(s, free, 5, false);
        if (r.est_sse < best.est_sse) best = std::move(r);
      }
      cands.push_back({e, std::move(best)});
    }
    if (cands.empty()) break;
    std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) { return a.s.est_sse < b.s.est_sse; });
    struct Refit {
      std::size_t e;
      Scored s;
      std::size_t signal;
      double gain;
      std::string reason;
      bool pass;
      double se;
    };
    std::vector<Refit> refits;
    const double neff = n_eff(current);  // every candidate of the round is compared at this one
    for (std::size_t c = 0; c < cands.size(); ++c) {
      ScreenedCandidate sc;
      sc.cause = effects[cands[c].e].cause;
      sc.round = round;
      sc.estimation_cost = cands[c].s.est_sse;
      if (static_cast<int>(c) >= opt.refit_top) {
        sc.reason = "not among the best " + std::to_string(opt.refit_top) + " in screening";
        d.screened.push_back(sc);
        continue;
      }
      const std::size_t e = cands[c].e;
      say("round " + std::to_string(round) + ": refitting " + effects[e].cause);
      auto act = active;
      act.push_back(e);
      Scored s = fit(cands[c].s.theta, free_for(act), 30, true);
      std::size_t sig = 0;
      double gain = -1e9;
      for (std::size_t o = 0; o < outs.size(); ++o)
        if (s.fit[o] - current.fit[o] > gain) {
          gain = s.fit[o] - current.fit[o];
          sig = o;
        }
      // Standard error of the gain: block bootstrap over 10 held-out sub-blocks,
      // each resample scored as a whole (a sub-block alone can have too little
      // variance for a meaningful fit percent).
      const double se = [&] {
        const std::size_t nb = 10;
        std::vector<std::array<double, 4>> st(nb);  // e_cur^2, e_new^2, y, y^2
        for (std::size_t k = 0; k < nb; ++k) {
          const std::size_t b0 = val_begin + (n - val_begin) * k / nb, e0 = val_begin + (n - val_begin) * (k + 1) / nb;
          std::array<double, 4> a{0, 0, 0, 0};
          for (std::size_t i = b0; i < e0; ++i) {
            const double y = outs[sig].measured[i];
            a[0] += (y - current.y[sig][i]) * (y - current.y[sig][i]);
            a[1] += (y - s.y[sig][i]) * (y - s.y[sig][i]);
            a[2] += y;
            a[3] += y * y;
          }
          st[k] = a;
        }
        std::mt19937 rng(777);
        std::uniform_int_distribution<std::size_t> pick(0, nb - 1);
        const double cnt = static_cast<double>(n - val_begin);
        double sy = 0.0, sy2 = 0.0;
        for (const auto& q : st) sy += q[2], sy2 += q[3];
        const double var_all = sy2 - sy * sy / cnt;
        double m1 = 0.0, m2 = 0.0;
        const int B = 200;
        for (int r = 0; r < B; ++r) {
          std::array<double, 4> a{0, 0, 0, 0};
          for (std::size_t k = 0; k < nb; ++k) {
            const auto& q = st[pick(rng)];
            for (int j = 0; j < 4; ++j) a[static_cast<std::size_t>(j)] += q[static_cast<std::size_t>(j)];
          }
          const double var = var_all;  // fixed denominator: the held-out variance
          const double g = var > 0 ? 100.0 * (std::sqrt(a[0] / var) - std::sqrt(a[1] / var)) : 0.0;
          m1 += g;
          m2 += g * g;
        }
        m1 /= B;
        return std::sqrt(std::max(0.0, m2 / B - m1 * m1));
      }();
      std::string reason;
      const double need = std::max(opt.min_gain, 2.0 * se);
      if (!(gain >= need)) reason = "held-out gain " + fmt(gain, 3) + " pp below " + fmt(need, 3) + " pp";
      bool significant = false;
      for (std::size_t j = 0; j < effects[e].params.size(); ++j) {
        const auto& ps = effects[e].params[j];
        if (!ps.strength) continue;
        const double val = s.theta[L.offset[e] + j], sg = s.sigma[L.offset[e] + j];
        if (std::isfinite(sg) && std::abs(val - ps.null) >= 3.0 * sg) significant = true;
      }
      if (reason.empty() && !significant) reason = "effect strength not significant (< 3 sigma)";
      std::size_t k_cur = L.n_base, k_new = L.n_base + effects[e].params.size();
      for (auto a : active) k_cur += effects[a].params.size(), k_new += effects[a].params.size();
      if (reason.empty() && !(bic(s, k_new, neff) < bic(current, k_cur, neff))) reason = "BIC (with N_eff) not lower";
      sc.refitted = true;
      sc.gain_percent_points = gain;
      sc.signal = outs[sig].name;
      sc.reason = reason.empty() ? "passes" : reason;
      say("  " + effects[e].cause + ": gain " + fmt(gain, 3) + " pp on " + outs[sig].name + " (" + sc.reason + ")");
      d.screened.push_back(sc);
      refits.push_back({e, std::move(s), sig, gain, reason, reason.empty(), se});
    }
    const Refit* winner = nullptr;
    for (const auto& r : refits)
      if (r.pass && (!winner || r.gain > winner->gain)) winner = &r;
    if (!winner) break;
    // Parsimony among the passing: a candidate with fewer parameters whose gain
    // is within 10 % of the winner's (at least 0.5 pp) wins the tie.
    {
      const double margin = std::max(0.5, 0.1 * winner->gain);
      for (const auto& r : refits)
        if (r.pass && r.gain >= winner->gain - margin &&
            effects[r.e].params.size() < effects[winner->e].params.size())
          winner = &r;
    }
    for (auto& sc : d.screened)
      if (sc.round == round && sc.cause == effects[winner->e].cause) sc.accepted = true;

    // Confidence: block bootstrap over 10 held-out sub-blocks; the share of
    // resamples in which the winner has the largest gain and at least g_min.
    const std::size_t sig = winner->signal;
    const std::size_t nb = 10;
    auto block_stats = [&](const std::vector<double>& ysim) {
      std::vector<std::array<double, 3>> st(nb);  // sum e^2, sum y, sum y^2
      for (std::size_t k = 0; k < nb; ++k) {
        const std::size_t b = val_begin + (n - val_begin) * k / nb, en = val_begin + (n - val_begin) * (k + 1) / nb;
        std::array<double, 3> a{0, 0, 0};
        for (std::size_t i = b; i < en; ++i) {
          const double y = outs[sig].measured[i];
          a[0] += (y - ysim[i]) * (y - ysim[i]);
          a[1] += y;
          a[2] += y * y;
        }
        st[k] = a;
      }
      return st;
    };
    auto cur_st = block_stats(current.y[sig]);
    std::vector<std::vector<std::array<double, 3>>> cand_st;
    for (const auto& r : refits) cand_st.push_back(block_stats(r.s.y[sig]));
    std::mt19937 rng(12345);
    std::uniform_int_distribution<std::size_t> pick(0, nb - 1);
    int wins = 0;
    const int B = 400;
    const std::size_t per_block = (n - val_begin) / nb;
    for (int bsi = 0; bsi < B; ++bsi) {
      std::vector<std::size_t> sel(nb);
      for (auto& s : sel) s = pick(rng);
      auto fitp = [&](const std::vector<std::array<double, 3>>& st) {
        double e2 = 0, sy = 0, sy2 = 0;
        for (auto s : sel) e2 += st[s][0], sy += st[s][1], sy2 += st[s][2];
        const double cnt = static_cast<double>(per_block * nb);
        const double var = sy2 - sy * sy / cnt;
        return var > 0 ? 100.0 * (1.0 - std::sqrt(e2 / var)) : 0.0;
      };
      const double fc = fitp(cur_st);
      double best_gain = -1e9;
      std::size_t best_i = 0;
      for (std::size_t r = 0; r < refits.size(); ++r) {
        const double g = fitp(cand_st[r]) - fc;
        if (g > best_gain) best_gain = g, best_i = r;
      }
      if (&refits[best_i] == winner && best_gain >= opt.min_gain) ++wins;
    }

    const std::size_t e = winner->e;
    CauseResult cr;
    cr.cause = effects[e].cause;
    cr.confidence = static_cast<double>(wins) / B;
    cr.signal = outs[sig].name;
    cr.baseline_fit_percent = current.fit[sig];
    cr.extended_fit_percent = winner->s.fit[sig];
    cr.gain_percent_points = winner->gain;
    for (std::size_t j = 0; j < effects[e].params.size(); ++j) {
      const auto& ps = effects[e].params[j];
      cr.parameters.push_back({ps.name, ps.unit, winner->s.theta[L.offset[e] + j], winner->s.sigma[L.offset[e] + j]});
    }
    // Evidence: the refit numbers and the conditional statistics of the
    // residual before the effect on its indicator.
    const auto ind = model.indicator(cr.cause);
    const auto res_before = residual_of(current, sig);
    std::ostringstream ev;
    ev << effects[e].description << ". Held-out fit of " << cr.signal << " " << fmt(cr.baseline_fit_percent) << " % -> "
       << fmt(cr.extended_fit_percent) << " % (free-run replay)";
    for (const auto& pv : cr.parameters)
      ev << "; " << pv.name << " = " << fmt(pv.value) << " +- " << fmt(pv.sigma, 2) << " " << pv.unit;
    if (!ind.name.empty()) {
      const double r2a = binned_r2(ind.values, res_before, val_begin, n);
      const auto res_after = residual_of(winner->s, sig);
      const double r2b = binned_r2(ind.values, res_after, val_begin, n);
      ev << "; residual of " << cr.signal << " explained by " << ind.name << " (binned): R2 " << fmt(r2a, 2)
         << " before, " << fmt(r2b, 2) << " after";
      Diagnosis::CausePlot cp;
      cp.cause = cr.cause;
      cp.indicator_name = ind.name;
      cp.signal = cr.signal;
      cp.indicator = ind.values;
      cp.residual = res_before;
      cp.effect_term = model.effect_term(cr.cause, winner->s.theta);
      d.cause_plots.push_back(std::move(cp));
    }
    ev << "; beat the other refitted candidates in " << fmt(100.0 * cr.confidence, 3)
       << " % of block-bootstrap resamples of the held-out part";
    cr.evidence = ev.str();
    say("accepted " + cr.cause + " (gain " + fmt(cr.gain_percent_points, 3) + " pp on " + cr.signal + ")");
    d.causes.push_back(cr);
    active.push_back(e);
    current = winner->s;
    // a rejected candidate stays in the pool: with another effect in, it may earn its place
  }

  // Backward check: every kept effect must still earn its place given the others.
  if (active.size() > 1) {
    for (std::size_t k = 0; k < active.size();) {
      std::vector<std::size_t> others;
      for (std::size_t j = 0; j < active.size(); ++j)
        if (j != k) others.push_back(active[j]);
      auto start = current.theta;
      for (std::size_t j = 0; j < effects[active[k]].params.size(); ++j)
        start[L.offset[active[k]] + j] = effects[active[k]].params[j].null;
      say("backward check: without " + effects[active[k]].cause);
      const Scored without = fit(start, free_for(others), 60, false);
      double best = -1e9;
      for (std::size_t o = 0; o < outs.size(); ++o) best = std::max(best, current.fit[o] - without.fit[o]);
      if (best < opt.min_gain) {
        say("  dropped " + effects[active[k]].cause + " (only " + fmt(best, 3) + " pp given the others)");
        const std::string c = effects[active[k]].cause;
        d.causes.erase(std::remove_if(d.causes.begin(), d.causes.end(), [&](auto& r) { return r.cause == c; }),
                       d.causes.end());
        active.erase(active.begin() + static_cast<std::ptrdiff_t>(k));
        current = without;
      } else {
        ++k;
      }
    }
  }

  d.cause = d.causes.empty() ? "none" : d.causes.front().cause;
  {
    const auto fr = free_for(active);
    for (std::size_t i = 0; i < L.specs.size(); ++i)
      if (fr[i]) d.final_parameters.push_back({L.specs[i].name, L.specs[i].unit, current.theta[i], current.sigma.empty() ? 0.0 : current.sigma[i]});
    // Each named cause reports its parameters from the final joint fit: the
    // values of the round that accepted it were fitted without the effects
    // added later, which may have carried part of its work.
    for (auto& cr : d.causes)
      for (auto e : active)
        if (effects[e].cause == cr.cause)
          for (std::size_t j = 0; j < cr.parameters.size() && j < effects[e].params.size(); ++j) {
            cr.parameters[j].value = current.theta[L.offset[e] + j];
            if (!current.sigma.empty()) cr.parameters[j].sigma = current.sigma[L.offset[e] + j];
          }
  }
  for (std::size_t o = 0; o < outs.size(); ++o) {
    d.baseline_fit_percent[outs[o].name] = base.fit[o];
    d.extended_fit_percent[outs[o].name] = current.fit[o];
  }
  std::ostringstream v;
  v << "contiguous split: the first " << fmt(100.0 * (1.0 - opt.holdout_fraction), 3) << " % of the record ("
    << n_est << " of " << n << " samples, after a " << init
    << "-sample initialisation window) for fitting, the last " << fmt(100.0 * opt.holdout_fraction, 3)
    << " % held out; fits above are free-run simulations of the whole record with the fitted parameters, scored "
       "on the held-out samples only; "
    << model.replay();
  d.validation = v.str();
  d.t = model.time();
  d.validation_start = val_begin;
  for (std::size_t o = 0; o < outs.size(); ++o) {
    d.output_names.push_back(outs[o].name);
    d.measured.push_back(outs[o].measured);
    d.y_baseline.push_back(base.y[o]);
    d.y_extended.push_back(current.y[o]);
  }
  d.elapsed_s = seconds_since(t0);
  say("done: cause " + d.cause);
  return d;
}

}  // namespace rigctl::diag
