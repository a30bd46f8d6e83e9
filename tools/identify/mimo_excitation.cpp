#include "tools/identify/mimo_excitation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::vector<double> one_period(const std::vector<std::size_t>& lines, const std::vector<double>& phases, std::size_t n,
                               double amplitude) {
  std::vector<double> x(n, 0.0);
  for (std::size_t l = 0; l < lines.size(); ++l) {
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += std::cos(kTwoPi * static_cast<double>(lines[l] * i % n) / static_cast<double>(n) + phases[l]);
    }
  }
  double peak = 0.0;
  for (double v : x) peak = std::max(peak, std::abs(v));
  for (double& v : x) v *= amplitude / peak;
  return x;
}

}  // namespace

MimoExcitation orthogonal_multisines(const std::vector<std::size_t>& lines, std::size_t n, std::size_t drives,
                                     std::size_t realisations, double amplitude, uint64_t seed) {
  if (drives == 0 || realisations < drives) throw std::invalid_argument("mimo excitation: needs at least as many realisations as drives");
  if (lines.empty()) throw std::invalid_argument("mimo excitation: no line to excite");
  for (std::size_t k : lines) {
    if (k == 0 || 2 * k >= n) throw std::invalid_argument("mimo excitation: line " + std::to_string(k) + " outside (0, Nyquist)");
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, kTwoPi);
  std::vector<std::vector<double>> base(drives, std::vector<double>(lines.size()));
  for (auto& drive : base) {
    for (double& p : drive) p = uniform(rng);
  }
  MimoExcitation e{n, realisations, {}};
  for (std::size_t r = 0; r < realisations; ++r) {
    std::vector<std::vector<double>> per_drive;
    for (std::size_t m = 0; m < drives; ++m) {
      std::vector<double> phases = base[m];
      const double rotation = kTwoPi * static_cast<double>(r * m) / static_cast<double>(realisations);
      for (double& p : phases) p += rotation;
      per_drive.push_back(one_period(lines, phases, n, amplitude));
    }
    e.periods.push_back(std::move(per_drive));
  }
  return e;
}

std::vector<std::vector<double>> played_records(const MimoExcitation& e, std::size_t settle) {
  const std::size_t drives = e.periods.empty() ? 0 : e.periods.front().size();
  std::vector<std::vector<double>> out(drives);
  for (const auto& realisation : e.periods) {
    for (std::size_t m = 0; m < drives; ++m) {
      for (std::size_t p = 0; p <= settle; ++p) out[m].insert(out[m].end(), realisation[m].begin(), realisation[m].end());
    }
  }
  return out;
}

std::vector<std::vector<double>> steady_periods(const std::vector<std::vector<double>>& recorded, const MimoExcitation& e,
                                                std::size_t settle) {
  const std::size_t block = (settle + 1) * e.period_ticks;
  std::vector<std::vector<double>> out(recorded.size());
  for (std::size_t c = 0; c < recorded.size(); ++c) {
    if (recorded[c].size() < block * e.realisations) throw std::invalid_argument("mimo excitation: a recorded channel is shorter than what was played");
    for (std::size_t r = 0; r < e.realisations; ++r) {
      const auto first = recorded[c].begin() + static_cast<std::ptrdiff_t>(r * block + settle * e.period_ticks);
      out[c].insert(out[c].end(), first, first + static_cast<std::ptrdiff_t>(e.period_ticks));
    }
  }
  return out;
}

}  // namespace rigctl
