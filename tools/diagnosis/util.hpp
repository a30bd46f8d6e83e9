// Small numerical helpers shared by the diagnosis sub-models (tools/diagnosis/models/*.cpp).
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "tools/diagnosis/model.hpp"

namespace rigctl::diag {

inline std::vector<double> central_diff(const std::vector<double>& x, double dt) {
  const std::size_t n = x.size();
  std::vector<double> v(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1 < n ? i + 1 : n - 1;
    v[i] = b > a ? (x[b] - x[a]) / (static_cast<double>(b - a) * dt) : 0.0;
  }
  return v;
}

// Value of a uniformly sampled series at fractional sample position s (clamped).
inline double at(const std::vector<double>& y, double s) {
  if (s <= 0.0) return y.front();
  const double last = static_cast<double>(y.size() - 1);
  if (s >= last) return y.back();
  const auto i = static_cast<std::size_t>(s);
  const double a = s - static_cast<double>(i);
  return y[i] + a * (y[i + 1] - y[i]);
}

// Delays a series by tau (linear interpolation), holding the first value before the start.
inline void delay(std::vector<double>& y, double tau, double dt) {
  if (tau <= 0.0) return;
  const std::vector<double> src = y;
  const double shift = tau / dt;
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = at(src, static_cast<double>(i) - shift);
}

// Implicit (Moreau) velocity update of a mass with viscous and Coulomb
// friction under force f over a step h: sticks exactly, never chatters.
// cp, cn >= 0: Coulomb levels for positive and negative motion; dp, dn >= 0 viscous.
inline double implicit_velocity(double m, double v, double f, double h, double cp, double cn, double dp, double dn) {
  const double a = m * v + h * f;
  if (a > h * cp) return (a - h * cp) / (m + h * dp);
  if (a < -h * cn) return (a + h * cn) / (m + h * dn);
  return 0.0;
}

inline ParamSpec P(const std::string& name, const std::string& unit, double init, double lo, double hi, double scale,
            double null = 0.0, bool strength = false, std::vector<double> starts = {}) {
  ParamSpec p;
  p.name = name;
  p.unit = unit;
  p.init = init;
  p.lo = lo;
  p.hi = hi;
  p.scale = scale;
  p.null = null;
  p.strength = strength;
  p.starts = std::move(starts);
  return p;
}

// A baseline parameter with a prior of relative tolerance `tol` about its
// nominal value (docs/diagnosis.md 4).
inline ParamSpec Prior(const std::string& name, const std::string& unit, double nominal, double tol,
                       double lo_factor = 0.3, double hi_factor = 3.0) {
  ParamSpec p = P(name, unit, nominal, nominal * lo_factor, nominal * hi_factor, std::abs(nominal) * tol);
  p.prior = tol;
  return p;
}

// The same parameter read as `cause` when it departs beyond its tolerance
// band on the side `toward` (-1 below nominal, +1 above; ParamSpec::stands_for).
inline ParamSpec StandsFor(ParamSpec p, const std::string& cause, int toward) {
  p.stands_for = cause;
  p.toward = toward;
  return p;
}

// An effect's parameter that acts on one sensor channel (ParamSpec::channel).
inline ParamSpec OnChannel(ParamSpec p, const std::string& channel) {
  p.channel = channel;
  return p;
}

// The effect's form index (ParamSpec::form), starting at form 0; `screened`:
// further forms the screening starts from as well (a form the first cannot
// stand in for, as a start grid does for a non-convex scalar).
inline ParamSpec FormIndex(std::vector<double> screened = {}) {
  ParamSpec p = P("form", "1", 0.0, 0.0, 1e3, 1.0, 0.0, false, std::move(screened));
  p.form = true;
  return p;
}

// A baseline parameter of the loop's I/O timing [s] within [0, hi]
// (ParamSpec::timing), starting at `init`.
inline ParamSpec Timing(const std::string& name, double init, double hi, double scale) {
  ParamSpec p = P(name, "s", init, 0.0, hi, scale);
  p.timing = true;
  return p;
}

}  // namespace rigctl::diag
