#include "tools/diagnosis/criteria.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

namespace rigctl::diag {

namespace {
std::string fmt(double v) {
  std::ostringstream os;
  os << std::setprecision(3) << v;
  return os.str();
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

double bic(double sse, std::size_t k, double n_eff, std::size_t n) {
  return n_eff * std::log(std::max(sse, 1e-300) / static_cast<double>(std::max<std::size_t>(n, 1))) +
         static_cast<double>(k) * std::log(n_eff);
}

std::vector<std::vector<double>> bootstrap_fits(const std::vector<double>& y,
                                                const std::vector<const std::vector<double>*>& sims,
                                                std::size_t begin, std::size_t end, int resamples, unsigned seed,
                                                std::size_t blocks, const std::vector<int>& strata) {
  // Per block: sum of squared errors of each simulation.
  std::vector<std::vector<double>> sse(blocks, std::vector<double>(sims.size(), 0.0));
  double sy = 0.0, sy2 = 0.0;
  for (std::size_t k = 0; k < blocks; ++k) {
    const std::size_t b = begin + (end - begin) * k / blocks, e = begin + (end - begin) * (k + 1) / blocks;
    for (std::size_t i = b; i < e; ++i) {
      sy += y[i], sy2 += y[i] * y[i];
      for (std::size_t s = 0; s < sims.size(); ++s) {
        const double d = y[i] - (*sims[s])[i];
        sse[k][s] += d * d;
      }
    }
  }
  const double cnt = static_cast<double>(end - begin);
  const double var = sy2 - sy * sy / cnt;  // fixed denominator: the held-out variance
  // The sub-blocks each one may be replaced by: its stratum's, or all.
  std::vector<std::vector<std::size_t>> pool(blocks);
  for (std::size_t k = 0; k < blocks; ++k)
    for (std::size_t j = 0; j < blocks; ++j)
      if (strata.size() != blocks || strata[j] == strata[k]) pool[k].push_back(j);
  std::mt19937 rng(seed);
  std::vector<std::vector<double>> out(static_cast<std::size_t>(resamples), std::vector<double>(sims.size(), 0.0));
  for (auto& row : out) {
    std::vector<double> acc(sims.size(), 0.0);
    for (std::size_t k = 0; k < blocks; ++k) {
      std::uniform_int_distribution<std::size_t> pick(0, pool[k].size() - 1);
      const auto& q = sse[pool[k][pick(rng)]];
      for (std::size_t s = 0; s < sims.size(); ++s) acc[s] += q[s];
    }
    for (std::size_t s = 0; s < sims.size(); ++s) row[s] = var > 0.0 ? 100.0 * (1.0 - std::sqrt(acc[s] / var)) : 0.0;
  }
  return out;
}

std::vector<int> activity_strata(const std::vector<double>& a, const std::vector<double>& b, std::size_t begin,
                                 std::size_t end, std::size_t blocks) {
  // A tenth of the largest change: a lift-off burst changes its sub-blocks'
  // prediction 100 x more than the rest; a global effect's sub-blocks
  // differ by a few times at most.
  constexpr double kActiveShare = 0.1;
  end = std::min({end, a.size(), b.size()});
  if (end <= begin + blocks) return {};
  std::vector<double> ms(blocks, 0.0);
  for (std::size_t k = 0; k < blocks; ++k) {
    const std::size_t lo = begin + (end - begin) * k / blocks, hi = begin + (end - begin) * (k + 1) / blocks;
    for (std::size_t i = lo; i < hi; ++i) ms[k] += (a[i] - b[i]) * (a[i] - b[i]);
  }
  const double top = *std::max_element(ms.begin(), ms.end());
  if (!(top > 0.0)) return {};
  std::vector<int> s(blocks);
  for (std::size_t k = 0; k < blocks; ++k) s[k] = ms[k] >= kActiveShare * top ? 1 : 0;
  const auto active = static_cast<std::size_t>(std::count(s.begin(), s.end(), 1));
  if (active < 2 || active == blocks) return {};
  return s;
}

double gain_standard_error(const std::vector<std::vector<double>>& fits, std::size_t c, std::size_t cur) {
  if (fits.empty()) return 0.0;
  double m1 = 0.0, m2 = 0.0;
  for (const auto& r : fits) {
    const double g = r[c] - r[cur];
    m1 += g, m2 += g * g;
  }
  const double n = static_cast<double>(fits.size());
  m1 /= n;
  return std::sqrt(std::max(0.0, m2 / n - m1 * m1));
}

bool misfits_beyond_noise(double excess, double fit) { return fit < kUnexplainedFit && excess >= kUnexplainedExcess; }

bool explains_misfit(const CandidateEvidence& c) {
  if (!misfits_beyond_noise(c.excess_before, c.fit_before)) return false;
  const double before = c.excess_before * c.excess_before - 1.0, after = c.excess_after * c.excess_after - 1.0;
  return after <= (1.0 - kExplainedShare) * before;
}

double gain_floor(const CandidateEvidence& c, const DiagnoseOptions& o) {
  return explains_misfit(c) ? o.explained_min_gain : o.min_gain;
}

std::string rejection(const CandidateEvidence& c, const DiagnoseOptions& o) {
  const double need = std::max(gain_floor(c, o), 2.0 * c.se);
  if (!(c.gain >= need)) return "held-out gain " + fmt(c.gain) + " pp below " + fmt(need) + " pp";
  const bool obvious = c.gain >= o.strong_gain && c.gain >= o.strong_se * c.se;
  if (!c.significant && !obvious)
    return "effect strength not significant (< 3 sigma) and the gain " + fmt(c.gain) + " pp below the " +
           fmt(std::max(o.strong_gain, o.strong_se * c.se)) + " pp that would stand on its own";
  if (!(c.bic_new < c.bic_current)) return "BIC (with N_eff) not lower";
  return {};
}

bool about_equal(double a, double b, const DiagnoseOptions& o) {
  return std::abs(a - b) < std::max(o.ambiguity_margin, 0.1 * std::max(std::abs(a), std::abs(b)));
}

}  // namespace rigctl::diag
