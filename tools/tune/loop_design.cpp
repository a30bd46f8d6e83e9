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

// Ke a + Kv b + Kp c = L for a given Kp: two real equations for Ke and Kv.
std::optional<LoopGains> pvp_at(const PlantGrid& p, LoopGains g, const DesignTarget& t, double fc, double kp) {
  const Complex a = p.position(fc);
  const Complex b = velocity_estimate(g, fc) * a;
  const Complex c = pressure_path(g, fc) * p.pressure(fc);
  const Complex rhs = target_loop(t) - kp * c;
  const double det = a.real() * b.imag() - a.imag() * b.real();
  if (std::abs(det) < 1e-300) return std::nullopt;
  g.ke = (rhs.real() * b.imag() - rhs.imag() * b.real()) / det;
  g.kv = (a.real() * rhs.imag() - a.imag() * rhs.real()) / det;
  g.kp_pressure = kp;
  if (!(g.ke > 0.0 && g.kv >= 0.0)) return std::nullopt;
  return g;
}

double stiffness(const LoopGains& g) { return g.kind == ControllerKind::kPi ? g.ki : g.ke; }

LoopDesign judge(const PlantGrid& p, const LoopGains& g, const DesignTarget& t, double fc) {
  LoopDesign d{g, margins_of(p, g), true, ""};
  const Margins& m = d.margins;
  if (!(std::abs(m.crossover_hz - fc) <= 0.03 * fc)) {
    d.meets_target = false;
    d.note = "|L| crosses 1 elsewhere in the band (another crossover)";
  } else if (m.gain_margin_db < t.min_gain_margin_db) {
    d.meets_target = false;
    d.note = "gain margin below " + std::to_string(t.min_gain_margin_db) + " dB";
  } else if (m.peak_sensitivity > t.max_sensitivity) {
    d.meets_target = false;
    d.note = "sensitivity peak above " + std::to_string(t.max_sensitivity);
  }
  return d;
}

// Every candidate gain set at one crossover.
std::vector<LoopGains> candidates_at(const PlantGrid& p, const LoopGains& base, const DesignTarget& t, double fc) {
  std::vector<LoopGains> out;
  if (base.kind == ControllerKind::kPi) {
    if (auto g = pi_at(p, base, t, fc)) out.push_back(*g);
    return out;
  }
  // Pressure gains from none up to 1e-3 V/Pa (100 V/bar, far beyond any use).
  out.reserve(41);
  for (int i = -1; i < 40; ++i) {
    const double kp = i < 0 ? 0.0 : 1e-8 * std::pow(10.0, 5.0 * i / 39.0);
    if (auto g = pvp_at(p, base, t, fc, kp)) out.push_back(*g);
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
  std::vector<double> crossovers = t.crossover_hz ? std::vector<double>{*t.crossover_hz} : p.log_grid(kCrossoverPoints);
  std::optional<LoopDesign> best, closest;
  for (double fc : crossovers) {
    if (fc < p.f_min() || fc > p.f_max()) continue;
    for (const LoopGains& g : candidates_at(p, base, t, fc)) {
      LoopDesign d = judge(p, g, t, fc);
      if (d.meets_target && (!best || stiffness(d.gains) > stiffness(best->gains))) best = d;
      if (!closest) closest = d;
    }
  }
  if (best) return *best;
  if (t.crossover_hz && closest) return *closest;  // as asked, with the reason it falls short
  throw std::runtime_error("no " + std::string(to_string(base.kind)) + " gains reach a " +
                           std::to_string(t.phase_margin_deg) + " degree phase margin" +
                           (t.crossover_hz ? " at " + std::to_string(*t.crossover_hz) + " Hz" : std::string(" anywhere in the band")) +
                           " with a 6 dB gain margin and a sensitivity peak of 2 on the measured plant");
}

}  // namespace rigctl
