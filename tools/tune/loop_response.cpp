#include "tools/tune/loop_response.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "tools/tune/plant_grid.hpp"

namespace rigctl {

namespace {

Complex z_inverse(double f_hz, double period_s) { return std::polar(1.0, -2.0 * std::numbers::pi * f_hz * period_s); }

}  // namespace

namespace {

// A line's trust: its coherence, lowered by the distortion beside it where
// the FRF has that (a nonlinear response is coherent but not linear).
void lower_by_quality(std::vector<double>& quality, const FrfData& frf, const FrfCurve& c) {
  const auto d = frf.distortion.find(c.response);
  for (std::size_t i = 0; i < quality.size(); ++i) {
    quality[i] = std::min(quality[i], c.coherence[i]);
    if (d != frf.distortion.end()) quality[i] = std::min(quality[i], 1.0 - d->second[i]);
  }
}

}  // namespace

PlantResponse PlantResponse::from_frf(const FrfData& frf) {
  PlantResponse p;
  p.frequency_hz = frf.frequency_hz;
  const FrfCurve& pos = frf.plant_of(frf.responses.at(0).name);
  p.position = pos.value;
  p.coherence.assign(p.frequency_hz.size(), 1.0);
  lower_by_quality(p.coherence, frf, pos);
  if (frf.responses.size() > 1) {
    const FrfCurve& pr = frf.plant_of(frf.responses[1].name);
    p.pressure = pr.value;
    lower_by_quality(p.coherence, frf, pr);
  }
  return p;
}

Complex pi_path(const LoopGains& g, double f_hz) {
  return g.kp + g.ki * g.period_s / (1.0 - z_inverse(f_hz, g.period_s));
}

Complex velocity_estimate(const LoopGains& g, double f_hz) {
  const double tau = g.velocity_filter_tau_s;
  const double alpha = tau > 0.0 ? 1.0 - std::exp(-g.period_s / tau) : 1.0;
  const Complex zi = z_inverse(f_hz, g.period_s);
  return alpha * (1.0 - zi) / g.period_s / (1.0 - (1.0 - alpha) * zi);
}

Complex pressure_path(const LoopGains& g, double f_hz) {
  if (!g.transient_pressure) return 1.0;
  const double a = g.transient_tau_s / (g.transient_tau_s + g.period_s);
  const Complex zi = z_inverse(f_hz, g.period_s);
  return a * (1.0 - zi) / (1.0 - a * zi);
}

Complex inner_loop_at(const LoopGains& g, double f, Complex position, Complex pressure) {
  if (g.kind != ControllerKind::kPvp) return 0.0;
  return g.kv * velocity_estimate(g, f) * position + g.kp_pressure * pressure_path(g, f) * pressure;
}

Complex loop_transfer_at(const LoopGains& g, double f, Complex position, Complex pressure) {
  switch (g.kind) {
    case ControllerKind::kPi: return pi_path(g, f) * position;
    case ControllerKind::kPvp: return g.ke * position / (1.0 + inner_loop_at(g, f, position, pressure));
    case ControllerKind::kPassive:
    case ControllerKind::kFuzzy:
    case ControllerKind::kSkyhook:
    case ControllerKind::kLqr: break;
  }
  throw std::invalid_argument("loop_transfer: not a position controller");
}

std::vector<Complex> loop_from_closed_loop(const std::vector<Complex>& t) {
  std::vector<Complex> out;
  for (const auto& z : t) out.push_back(z / (1.0 - z));
  return out;
}

std::vector<Complex> loop_transfer(const LoopGains& g, const PlantResponse& p) {
  if (g.kind == ControllerKind::kPvp && p.pressure.size() != p.position.size()) {
    throw std::invalid_argument("P+V+dP needs the plant's pressure response in the FRF");
  }
  std::vector<Complex> out;
  for (std::size_t i = 0; i < p.frequency_hz.size(); ++i) {
    out.push_back(loop_transfer_at(g, p.frequency_hz[i], p.position[i], p.pressure.empty() ? Complex{} : p.pressure[i]));
  }
  return out;
}

Margins closed_loop_margins(const FrfData& frf) {
  std::vector<double> f;
  std::vector<Complex> t;
  const FrfCurve& cl = frf.closed_loop.front();
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    if (cl.coherence[i] < kDesignCoherence) continue;
    f.push_back(frf.frequency_hz[i]);
    t.push_back(cl.value[i]);
  }
  return loop_margins(f, loop_from_closed_loop(t));
}

}  // namespace rigctl
