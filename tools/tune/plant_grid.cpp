#include "tools/tune/plant_grid.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "tools/tune/margins.hpp"

namespace rigctl {

namespace {

void split(const std::vector<Complex>& v, std::vector<double>& db, std::vector<double>& deg) {
  for (const auto& z : v) db.push_back(20.0 * std::log10(std::abs(z)));
  deg = unwrapped_phase_deg(v);
}

}  // namespace

PlantGrid::PlantGrid(const PlantResponse& m, double min_coherence) {
  std::vector<Complex> pos, pr;
  for (std::size_t i = 0; i < m.frequency_hz.size(); ++i) {
    if (m.coherence[i] < min_coherence) continue;
    f_.push_back(m.frequency_hz[i]);
    pos.push_back(m.position[i]);
    if (!m.pressure.empty()) pr.push_back(m.pressure[i]);
  }
  if (f_.size() < 3) throw std::invalid_argument("fewer than 3 frequencies with coherence >= " + std::to_string(min_coherence) + ": nothing to design on");
  split(pos, pos_db_, pos_deg_);
  has_pressure_ = !pr.empty();
  if (has_pressure_) split(pr, pr_db_, pr_deg_);
}

Complex PlantGrid::at(double f, const std::vector<double>& db, const std::vector<double>& deg) const {
  std::size_t i = 0;
  while (i + 2 < f_.size() && f > f_[i + 1]) ++i;
  const double t = (std::log(f) - std::log(f_[i])) / (std::log(f_[i + 1]) - std::log(f_[i]));
  const double m = db[i] + t * (db[i + 1] - db[i]);
  const double p = deg[i] + t * (deg[i + 1] - deg[i]);
  return std::polar(std::pow(10.0, m / 20.0), p * std::numbers::pi / 180.0);
}

std::vector<double> PlantGrid::log_grid(std::size_t points) const {
  std::vector<double> out;
  for (std::size_t i = 0; i < points; ++i) {
    out.push_back(f_min() * std::pow(f_max() / f_min(), static_cast<double>(i) / static_cast<double>(points - 1)));
  }
  return out;
}

std::vector<Complex> PlantGrid::loop(const LoopGains& g, const std::vector<double>& f_hz) const {
  std::vector<Complex> out;
  for (double f : f_hz) out.push_back(loop_transfer_at(g, f, position(f), pressure(f)));
  return out;
}

std::vector<Complex> PlantGrid::inner_loop(const LoopGains& g, const std::vector<double>& f_hz) const {
  std::vector<Complex> out;
  for (double f : f_hz) out.push_back(inner_loop_at(g, f, position(f), pressure(f)));
  return out;
}

}  // namespace rigctl
