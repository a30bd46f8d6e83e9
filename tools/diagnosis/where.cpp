// The "where" of a diagnosis (where.hpp, docs/diagnosis.md 3): the missing
// signal at each place of the model, reconstructed from the calibrated
// baseline's residual through the model's linearised inverse on a small
// feature library, scored on the held-out part.
#include "tools/diagnosis/where.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "tools/diagnosis/criteria.hpp"
#include "tools/diagnosis/evidence.hpp"
#include "tools/diagnosis/parallel.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {

namespace {

std::string fmt(double v, int prec = 3) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

// One column of the library: a measured feature scaled to unit rms (the
// regression's conditioning); `scale` turns its coefficient back into the
// place's unit per the feature's own unit.
struct Column {
  std::string name;
  std::vector<double> values;  // unit rms
  std::vector<double> raw;     // as measured (the report's plot)
  double scale = 1.0;          // rms of raw
  std::vector<int> from;       // the outputs it is measured from (RigModel::Feature::from)
};

double rms(const std::vector<double>& x) {
  double ss = 0.0;
  for (double v : x) ss += v * v;
  return x.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(x.size()));
}

void add_column(std::vector<Column>& lib, std::string name, std::vector<double> raw, std::vector<int> from = {}) {
  const double s = rms(raw);
  if (!(s > 0.0) || !std::isfinite(s)) return;  // a feature that never moves explains nothing
  Column c{std::move(name), raw, raw, s, std::move(from)};
  for (auto& v : c.values) v /= s;
  lib.push_back(std::move(c));
}

double mean(const std::vector<double>& x) {
  double m = 0.0;
  for (double v : x) m += v;
  return x.empty() ? 0.0 : m / static_cast<double>(x.size());
}

// Signed travel since the last reversal of a position: a reversal counts
// once the position has come back `band` from its extreme, so noise at rest
// does not restart it.
std::vector<double> travel_since_reversal(const std::vector<double>& x, double band) {
  std::vector<double> out(x.size(), 0.0);
  if (x.empty()) return out;
  int dir = 0;
  double anchor = x[0], extreme = x[0], hi = x[0], lo = x[0];
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double v = x[i];
    if (dir == 0) {  // the first motion: once it leaves the band
      hi = std::max(hi, v), lo = std::min(lo, v);
      if (hi - lo > band) dir = v >= hi ? 1 : -1, anchor = dir > 0 ? lo : hi, extreme = v;
    } else if (dir > 0) {
      if (v > extreme) extreme = v;
      else if (v < extreme - band) dir = -1, anchor = extreme, extreme = v;
    } else {
      if (v < extreme) extreme = v;
      else if (v > extreme + band) dir = 1, anchor = extreme, extreme = v;
    }
    out[i] = dir * std::abs(v - anchor);
  }
  return out;
}

// The library every place shares: a constant, and each measured feature of
// the rig in the forms its kind has. A velocity: its sign, smoothed over its
// own noise floor (never below 5 % of its rms: a friction's step is at the
// scale of the motion, not of the LSB), and its value. A command: its value
// and its part near null, clamped at a tenth of its rms (what a dead band
// takes away).
std::vector<Column> shared_library(const RigModel& model) {
  std::vector<Column> lib;
  add_column(lib, "constant", std::vector<double>(model.time().size(), 1.0));
  for (const auto& f : model.features()) {
    switch (f.kind) {
      case RigModel::FeatureKind::kVelocity: {
        const double band = std::max(noise_floor(f.values), 0.05 * rms(f.values));
        std::vector<double> s(f.values.size());
        for (std::size_t i = 0; i < s.size(); ++i) s[i] = band > 0.0 ? std::tanh(f.values[i] / band) : 0.0;
        add_column(lib, "sign(" + f.name + ")", std::move(s), f.from);
        add_column(lib, f.name, f.values, f.from);
        break;
      }
      case RigModel::FeatureKind::kCommand: {
        const double edge = 0.1 * rms(f.values);
        std::vector<double> s(f.values.size());
        for (std::size_t i = 0; i < s.size(); ++i) s[i] = std::clamp(f.values[i], -edge, edge);
        add_column(lib, f.name + " near null", std::move(s), f.from);
        add_column(lib, f.name, f.values, f.from);
        break;
      }
      case RigModel::FeatureKind::kPosition: {
        // A reversal: back by four noise floors (a few LSB) from the extreme.
        const auto travel = travel_since_reversal(f.values, 4.0 * std::max(noise_floor(f.values), 1e-12));
        const double width = 0.1 * rms(travel);  // a hysteresis loop closes over a part of the stroke
        std::vector<double> sat(travel.size());
        for (std::size_t i = 0; i < sat.size(); ++i)
          sat[i] = width > 0.0 ? std::copysign(1.0 - std::exp(-std::abs(travel[i]) / width), travel[i]) : 0.0;
        add_column(lib, "travel of " + f.name + " since reversal", travel, f.from);
        add_column(lib, "saturating travel of " + f.name + " since reversal", std::move(sat), f.from);
        [[fallthrough]];
      }
      case RigModel::FeatureKind::kValue: {
        const double m = mean(f.values);  // the constant carries the level
        std::vector<double> c(f.values.size());
        for (std::size_t i = 0; i < c.size(); ++i) c[i] = f.values[i] - m;
        add_column(lib, f.name, std::move(c), f.from);
        break;
      }
    }
  }
  return lib;
}

// A sensor's own columns: the rate of the channel (a delay or a lag errs by
// about -tau dy/dt), its value (a gain error) and a drift. Taken from the
// calibrated replay, not the measurement, so the sensor's noise is not in
// the regressor.
std::vector<Column> sensor_columns(const Workspace& w, const Scored& s, std::size_t o) {
  std::vector<Column> lib;
  const double dt = w.n > 1 ? (w.model.time().back() - w.model.time().front()) / static_cast<double>(w.n - 1) : 1.0;
  const std::string& name = w.outs()[o].name;
  add_column(lib, "d" + name + "/dt (replayed)", central_diff(s.y[o], dt));
  const double m = mean(s.y[o]);
  std::vector<double> v(s.y[o].size()), t(w.n);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = s.y[o][i] - m;
  add_column(lib, name + " (replayed)", std::move(v));
  const double tm = mean(w.model.time());
  for (std::size_t i = 0; i < w.n; ++i) t[i] = w.model.time()[i] - tm;
  add_column(lib, "drift (t)", std::move(t));
  return lib;
}

// Normal equations of the weighted, stacked regression on the estimation
// part (est) and on the held-out part (val): G = R'R, b = R'r, rr = r'r.
struct Normal {
  Eigen::MatrixXd G;
  Eigen::VectorXd b;
  double rr = 0.0;
};

// The responses of every output to each column added at place p (unit
// coefficient), weighted as the fit weighs the outputs.
std::vector<std::vector<std::vector<double>>> responses(const Workspace& w, const Scored& s, std::size_t p,
                                                        const RigModel::Place& place,
                                                        const std::vector<Column>& lib) {
  std::vector<std::vector<std::vector<double>>> out(lib.size());
  const bool additive = place.output >= 0 && !place.in_loop;
  parallel_for(w.threads, lib.size(), [&](std::size_t k, std::size_t) {
    auto& resp = out[k];
    if (additive) {  // an error on an output after the replay: its response is the column itself
      resp.assign(w.outs().size(), std::vector<double>(w.n, 0.0));
      resp[static_cast<std::size_t>(place.output)] = lib[k].values;
      return;
    }
    std::vector<double> d(lib[k].values);
    for (auto& v : d) v *= place.scale;
    w.model.simulate_with_input(s.theta, p, d, resp);
    for (std::size_t o = 0; o < resp.size(); ++o)
      for (std::size_t i = 0; i < w.n; ++i) {
        resp[o][i] = (resp[o][i] - s.y[o][i]) / place.scale;
        if (!std::isfinite(resp[o][i])) resp[o][i] = 0.0;  // a replay that failed adds no information
      }
  });
  return out;
}

void normal_equations(const Workspace& w, const Scored& s, const std::vector<std::vector<std::vector<double>>>& R,
                      Normal& est, Normal& val) {
  const auto K = static_cast<Eigen::Index>(R.size());
  est.G = Eigen::MatrixXd::Zero(K, K), val.G = est.G;
  est.b = Eigen::VectorXd::Zero(K), val.b = est.b;
  est.rr = val.rr = 0.0;
  std::vector<double> row(R.size());
  for (std::size_t o = 0; o < w.outs().size(); ++o)
    for (std::size_t i = w.init; i < w.n; ++i) {
      const bool in_est = w.est_mask[i] != 0, in_val = i >= w.val_begin;
      if (!in_est && !in_val) continue;
      Normal& ne = in_est ? est : val;
      const double r = (w.outs()[o].measured[i] - s.y[o][i]) * w.weight[o];
      if (!std::isfinite(r)) continue;
      for (std::size_t k = 0; k < R.size(); ++k) row[k] = R[k][o][i] * w.weight[o];
      ne.rr += r * r;
      for (Eigen::Index a = 0; a < K; ++a) {
        ne.b(a) += row[static_cast<std::size_t>(a)] * r;
        for (Eigen::Index c = 0; c <= a; ++c) ne.G(a, c) += row[static_cast<std::size_t>(a)] * row[static_cast<std::size_t>(c)];
      }
    }
  est.G = est.G.selfadjointView<Eigen::Lower>();
  val.G = val.G.selfadjointView<Eigen::Lower>();
}

Eigen::VectorXd solve_on(const Normal& ne, const std::vector<Eigen::Index>& sel) {
  const auto m = static_cast<Eigen::Index>(sel.size());
  Eigen::MatrixXd G(m, m);
  Eigen::VectorXd b(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    b(a) = ne.b(sel[static_cast<std::size_t>(a)]);
    for (Eigen::Index c = 0; c < m; ++c) G(a, c) = ne.G(sel[static_cast<std::size_t>(a)], sel[static_cast<std::size_t>(c)]);
  }
  // A tiny ridge: two columns a place cannot tell apart (the sign of a
  // velocity and a constant over a one-way record) must not blow up.
  G.diagonal().array() += 1e-9 * std::max(1e-300, G.diagonal().maxCoeff());
  return G.ldlt().solve(b);
}

double sse_of(const Normal& ne, const std::vector<Eigen::Index>& sel, const Eigen::VectorXd& c) {
  double sse = ne.rr;
  for (std::size_t a = 0; a < sel.size(); ++a) {
    sse -= 2.0 * c(static_cast<Eigen::Index>(a)) * ne.b(sel[a]);
    for (std::size_t d = 0; d < sel.size(); ++d)
      sse += c(static_cast<Eigen::Index>(a)) * c(static_cast<Eigen::Index>(d)) * ne.G(sel[a], sel[d]);
  }
  return std::max(0.0, sse);
}

// Orthogonal matching pursuit on the estimation part: add the column that
// lowers the SSE most while the BIC at N_eff falls.
std::vector<Eigen::Index> pursue(const Normal& est, double n_eff) {
  std::vector<Eigen::Index> sel;
  double sse = est.rr;
  while (sel.size() < kWhereMaxRegressors) {
    Eigen::Index best = -1;
    double best_sse = sse;
    for (Eigen::Index k = 0; k < est.G.rows(); ++k) {
      if (std::find(sel.begin(), sel.end(), k) != sel.end() || !(est.G(k, k) > 0.0)) continue;
      auto trial = sel;
      trial.push_back(k);
      const double e = sse_of(est, trial, solve_on(est, trial));
      if (e < best_sse) best_sse = e, best = k;
    }
    if (best < 0 || !(n_eff * std::log(std::max(best_sse, 1e-300) / sse) + std::log(n_eff) < 0.0)) break;
    sel.push_back(best);
    sse = best_sse;
  }
  return sel;
}

struct PlaceFit {
  WherePlace place;
  std::vector<Eigen::Index> sel;
  Eigen::VectorXd coef;
  const std::vector<Column>* lib = nullptr;
};

PlaceFit fit_place(const Workspace& w, const Scored& s, std::size_t p, const RigModel::Place& place,
                   const std::vector<Column>& lib, double n_eff, double noise_val) {
  PlaceFit f;
  f.place.name = place.name;
  f.place.unit = place.unit;
  f.place.causes = place.causes;
  Normal est, val;
  normal_equations(w, s, responses(w, s, p, place, lib), est, val);
  f.sel = pursue(est, n_eff);
  f.coef = f.sel.empty() ? Eigen::VectorXd() : solve_on(est, f.sel);
  const double after = f.sel.empty() ? val.rr : sse_of(val, f.sel, f.coef);
  f.place.explained_share = val.rr > 0.0 ? 1.0 - after / val.rr : 0.0;
  const double above = val.rr - noise_val;
  f.place.share_above_noise = above > 0.0 ? std::clamp((val.rr - after) / above, 0.0, 1.0) : 0.0;
  for (std::size_t a = 0; a < f.sel.size(); ++a) {
    auto others = f.sel;
    others.erase(others.begin() + static_cast<std::ptrdiff_t>(a));
    const double without = others.empty() ? val.rr : sse_of(val, others, solve_on(est, others));
    const auto& col = lib[static_cast<std::size_t>(f.sel[a])];
    f.place.regressors.push_back({col.name, f.coef(static_cast<Eigen::Index>(a)) / col.scale,
                                  val.rr > 0.0 ? (without - after) / val.rr : 0.0});
  }
  std::vector<std::size_t> order(f.sel.size());
  for (std::size_t a = 0; a < order.size(); ++a) order[a] = a;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return f.place.regressors[a].share > f.place.regressors[b].share;
  });
  std::vector<WhereRegressor> regs;
  std::vector<Eigen::Index> sel;
  Eigen::VectorXd coef(static_cast<Eigen::Index>(order.size()));
  for (std::size_t a = 0; a < order.size(); ++a) {
    regs.push_back(f.place.regressors[order[a]]);
    sel.push_back(f.sel[order[a]]);
    coef(static_cast<Eigen::Index>(a)) = f.coef(static_cast<Eigen::Index>(order[a]));
  }
  f.place.regressors = std::move(regs);
  f.sel = std::move(sel);
  f.coef = std::move(coef);
  return f;
}

// Whether the baseline misfits some output beyond its noise floor.
bool misfits(const Workspace& w, const Scored& s) {
  for (std::size_t o = 0; o < w.outs().size(); ++o) {
    const double excess = w.noise[o] > 0.0 ? w.held_out_rms(s, o) / w.noise[o] : 0.0;
    if (misfits_beyond_noise(excess, s.fit[o])) return true;
  }
  return false;
}

std::string describe(const WherePlace& p, bool significant) {
  std::ostringstream os;
  os << p.name;
  if (!p.regressors.empty()) {
    os << " that follows";
    for (std::size_t a = 0; a < p.regressors.size(); ++a)
      os << (a ? (a + 1 == p.regressors.size() ? " and " : ", ") : " ") << p.regressors[a].feature << " ("
         << fmt(p.regressors[a].coefficient) << ")";
  }
  os << ": " << fmt(100.0 * p.explained_share, 3) << " % of the held-out residual, "
     << fmt(100.0 * p.share_above_noise, 3) << " % of its part above the noise"
     << (significant ? "" : " (not significant: too little of a misfit, or none beyond the noise)");
  return os.str();
}

}  // namespace

WhereResult locate(const Workspace& w, const Scored& s) {
  WhereResult r;
  const auto places = w.model.places();
  if (places.empty() || w.n <= w.val_begin) return r;
  r.computed = true;
  const auto shared = shared_library(w.model);
  const double n_eff = w.n_eff(s);
  double noise_val = 0.0;
  for (std::size_t o = 0; o < w.outs().size(); ++o)
    noise_val += w.weight[o] * w.weight[o] * w.noise[o] * w.noise[o] * static_cast<double>(w.n - w.val_begin);
  std::vector<PlaceFit> fits;
  std::vector<std::vector<Column>> libs(places.size());
  for (std::size_t p = 0; p < places.size(); ++p) {
    // A sensor errs by an offset, a delay or lag, a gain or a drift of its
    // own channel: its library is those. A sensor error free to follow the
    // motion's features would take any effect whose outputs it reads (the
    // hysteresis of a rotor is a dp level that follows theta), and one
    // following its own measurement would fit its residual exactly.
    for (const auto& c : shared)
      if (places[p].output < 0 || c.name == "constant") libs[p].push_back(c);
    if (places[p].output >= 0)
      for (auto& c : sensor_columns(w, s, static_cast<std::size_t>(places[p].output))) libs[p].push_back(std::move(c));
    fits.push_back(fit_place(w, s, p, places[p], libs[p], n_eff, noise_val));
    fits.back().lib = &libs[p];
    w.say("where: " + places[p].name + " explains " + fmt(100.0 * fits.back().place.explained_share, 3) +
          " % of the held-out residual");
  }
  std::stable_sort(fits.begin(), fits.end(), [](const PlaceFit& a, const PlaceFit& b) {
    return a.place.explained_share > b.place.explained_share;
  });
  for (const auto& f : fits) r.places.push_back(f.place);
  const PlaceFit& best = fits.front();
  r.significant = best.place.share_above_noise >= kWhereMinShare && misfits(w, s);
  r.sentence = describe(best.place, r.significant);
  r.signal.assign(w.n, 0.0);
  for (std::size_t a = 0; a < best.sel.size(); ++a) {
    const auto& col = (*best.lib)[static_cast<std::size_t>(best.sel[a])];
    for (std::size_t i = 0; i < w.n; ++i) r.signal[i] += best.coef(static_cast<Eigen::Index>(a)) * col.values[i];
  }
  if (!best.sel.empty()) {
    const auto& col = (*best.lib)[static_cast<std::size_t>(best.sel.front())];
    r.feature_name = col.name;
    r.feature_values = col.raw;
  }
  return r;
}

bool where_agrees(const WhereResult& where, const std::string& cause) {
  if (!where.significant || where.places.empty()) return true;
  const double bar = 0.8 * where.places.front().explained_share;
  for (const auto& p : where.places)
    if (p.explained_share >= bar && std::find(p.causes.begin(), p.causes.end(), cause) != p.causes.end()) return true;
  return false;
}

std::size_t where_promotion(const WhereResult& where, const std::vector<std::string>& screened, std::size_t top) {
  const auto causes = where_causes(where);
  auto enters = [&](const std::string& c) { return std::find(causes.begin(), causes.end(), c) != causes.end(); };
  if (causes.empty() || screened.size() <= top) return screened.size();
  for (std::size_t k = 0; k < top; ++k)
    if (enters(screened[k])) return screened.size();
  for (std::size_t k = top; k < screened.size(); ++k)
    if (enters(screened[k])) return k;
  return screened.size();
}

std::vector<std::string> where_causes(const WhereResult& where) {
  if (!where.significant || where.places.empty()) return {};
  return where.places.front().causes;
}

}  // namespace rigctl::diag
