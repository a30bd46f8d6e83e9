#include "tools/tune/loop_design.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr std::size_t kMarginPoints = 400;   // margins on this many log-spaced frequencies
constexpr std::size_t kCrossoverPoints = 80;  // crossovers tried without --bandwidth
constexpr double kDeg = std::numbers::pi / 180.0;

Complex target_loop(const DesignTarget& t) { return std::polar(1.0, (t.phase_margin_deg - 180.0) * kDeg); }

// kp, ki that put C(z) G at the target: C = kp + ki Ts (1/2 - j cot(w Ts / 2) / 2).
std::optional<LoopGains> pi_at(const PlantGrid& p, LoopGains g, const DesignTarget& t, double fc) {
  const Complex c = target_loop(t) / p.position(fc);
  const double half = std::numbers::pi * fc * g.period_s;
  g.ki = -2.0 * c.imag() / (g.period_s / std::tan(half));
  g.kp = c.real() - g.ki * g.period_s / 2.0;
  if (!(g.ki >= 0.0 && g.kp > 0.0)) return std::nullopt;
  return g;
}

// With the inner loop (Kv, Kp) fixed, the position loop is Ke M, M = G / (1
// + inner): Ke puts |L| = 1 where the angle of M is -180 + PM. Every such
// crossover in the band is a candidate (the first one above the lowest
// frequency where the phase reaches the line).
std::vector<LoopGains> pvp_with_inner(const PlantGrid& p, LoopGains g, const DesignTarget& t, const std::vector<double>& f) {
  std::vector<LoopGains> out;
  g.ke = 1.0;
  const auto m = p.loop(g, f);
  const auto phase = unwrapped_phase_deg(m);
  const double line = t.phase_margin_deg - 180.0;
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    if ((phase[i] - line) * (phase[i + 1] - line) > 0.0 || phase[i] == phase[i + 1]) continue;
    const double u = (line - phase[i]) / (phase[i + 1] - phase[i]);
    const double fc = std::exp(std::log(f[i]) + u * (std::log(f[i + 1]) - std::log(f[i])));
    g.ke = 1.0 / std::abs(loop_transfer_at(g.with_ke(1.0), fc, p.position(fc), p.pressure(fc)));
    out.push_back(g);
    g.ke = 1.0;
  }
  return out;
}

double stiffness(const LoopGains& g, const PlantGrid& p) {
  if (g.kind == ControllerKind::kPi) return g.ki;
  const double f = p.f_min();
  const double k = (Complex(0.0, 2.0 * std::numbers::pi * f) * p.position(f)).real();
  const double p0 = p.pressure(f).real();
  return g.ke * k / (1.0 + g.kv * k + g.kp_pressure * p0);
}

// The inner loop's own sensitivity peak (1 for PI, which has none).
double inner_sensitivity(const PlantGrid& p, const LoopGains& g) {
  double peak = 1.0;
  for (const auto& z : p.inner_loop(g, p.log_grid(kMarginPoints))) peak = std::max(peak, 1.0 / std::abs(1.0 + z));
  return peak;
}

LoopDesign judge(const PlantGrid& p, const LoopGains& g, const DesignTarget& t, double fc) {
  LoopDesign d{g, margins_of(p, g), true, ""};
  const Margins& m = d.margins;
  if (!(std::abs(m.crossover_hz - fc) <= 0.03 * fc)) {
    d.meets_target = false;
    d.note = "|L| crosses 1 elsewhere in the band (another crossover)";
  } else if (m.gain_margin_db < t.min_gain_margin_db) {
    d.meets_target = false;
    d.note = "gain margin below " + std::to_string(t.min_gain_margin_db) + " dB";
  } else if ((g.kind == ControllerKind::kPi ? g.kp : g.ke) > t.max_demand_gain) {
    d.meets_target = false;
    d.note = "demand gain above " + std::to_string(t.max_demand_gain) + ": the unfiltered step would saturate the valve";
  } else if (m.peak_sensitivity > t.max_sensitivity || inner_sensitivity(p, g) > t.max_sensitivity) {
    d.meets_target = false;
    d.note = "sensitivity peak above " + std::to_string(t.max_sensitivity);
  }
  return d;
}

// Every candidate gain set: PI at each crossover; P+V+dP over a grid of
// inner loops (Kv from none to 100 V s/rad, Kp from none to 1e-3 V/Pa, i.e.
// 100 V/bar: beyond any use), each at the crossovers its phase allows.
std::vector<std::pair<LoopGains, double>> candidates(const PlantGrid& p, const LoopGains& base, const DesignTarget& t,
                                                     const std::vector<double>& crossovers) {
  std::vector<std::pair<LoopGains, double>> out;
  if (base.kind == ControllerKind::kPi) {
    for (double fc : crossovers) {
      if (auto g = pi_at(p, base, t, fc)) out.emplace_back(*g, fc);
    }
    return out;
  }
  const auto f = p.log_grid(kMarginPoints);
  for (int i = -1; i < 30; ++i) {
    for (int j = -1; j < 20; ++j) {
      LoopGains g = base;
      g.kv = i < 0 ? 0.0 : 1e-3 * std::pow(10.0, 5.0 * i / 29.0);
      g.kp_pressure = j < 0 ? 0.0 : 1e-8 * std::pow(10.0, 5.0 * j / 19.0);
      for (const LoopGains& c : pvp_with_inner(p, g, t, f)) {
        const double fc = margins_of(p, c).crossover_hz;
        if (!t.crossover_hz || std::abs(fc - *t.crossover_hz) <= 0.05 * *t.crossover_hz) out.emplace_back(c, fc);
      }
    }
  }
  return out;
}

}  // namespace

Margins margins_of(const PlantGrid& p, const LoopGains& g) {
  const auto f = p.log_grid(kMarginPoints);
  return loop_margins(f, p.loop(g, f));
}

LoopDesign design_loop(const PlantGrid& p, const LoopGains& base, const DesignTarget& t) {
  if (base.kind == ControllerKind::kPvp && !p.has_pressure()) {
    throw std::runtime_error("P+V+dP tuning needs the plant's pressure response: identify with the pvp controller");
  }
  const std::vector<double> crossovers = t.crossover_hz ? std::vector<double>{*t.crossover_hz} : p.log_grid(kCrossoverPoints);
  std::optional<LoopDesign> best, closest;
  for (const auto& [g, fc] : candidates(p, base, t, crossovers)) {
    if (fc < p.f_min() || fc > p.f_max()) continue;
    LoopDesign d = judge(p, g, t, fc);
    if (d.meets_target && (!best || stiffness(d.gains, p) > stiffness(best->gains, p))) best = d;
    if (!closest) closest = d;
  }
  if (best) return *best;
  if (t.crossover_hz && closest) return *closest;  // as asked, with the reason it falls short
  throw std::runtime_error("no " + std::string(to_string(base.kind)) + " gains reach a " +
                           std::to_string(t.phase_margin_deg) + " degree phase margin" +
                           (t.crossover_hz ? " at " + std::to_string(*t.crossover_hz) + " Hz" : std::string(" anywhere in the band")) +
                           " with a 6 dB gain margin and a sensitivity peak of 2 on the measured plant");
}

}  // namespace rigctl
