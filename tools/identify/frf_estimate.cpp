#include "tools/identify/frf_estimate.hpp"

#include <algorithm>
#include <stdexcept>

namespace rigctl {

namespace {

double coherence(const CrossSpectra& s, std::size_t k, int i, int j) {
  const double denom = s.power(k, i) * s.power(k, j);
  return denom > 0.0 ? std::norm(s.at(k, i, j)) / denom : 0.0;
}

// Mean power on the bins within three of line k that were not excited.
double power_beside(const CrossSpectra& s, const std::vector<std::size_t>& lines, std::size_t k, int y) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t j = k > 3 ? k - 3 : 1; j <= k + 3 && j < s.frequency_hz.size(); ++j) {
    if (std::find(lines.begin(), lines.end(), j) != lines.end()) continue;
    sum += s.power(j, y);
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

}  // namespace

void estimate_frf(const IdentificationRecord& r, const WelchSettings& settings, double band_min_hz,
                  double band_max_hz, const std::vector<std::size_t>& bins, FrfData& out) {
  std::vector<std::span<const double>> signals{r.demand, r.command};
  signals.insert(signals.end(), r.responses.begin(), r.responses.end());
  const CrossSpectra s = welch(signals, settings);
  constexpr int kDemand = 0, kCommand = 1;

  out.frequency_hz.clear();
  out.command_coherence.clear();
  out.closed_loop.assign(r.responses.size(), {});
  out.plant.assign(r.responses.size(), {});
  out.noise_floor.clear();
  out.response_psd.clear();
  out.distortion.clear();
  for (std::size_t c = 0; c < r.responses.size(); ++c) {
    out.closed_loop[c].response = out.plant[c].response = out.responses.at(c).name;
  }
  auto& command_noise = out.noise_floor[out.command.name];
  auto& command_psd = out.response_psd[out.command.name];
  for (std::size_t k = 1; k < s.frequency_hz.size(); ++k) {
    const double f = s.frequency_hz[k];
    if (f < band_min_hz - 1e-9 || f > band_max_hz + 1e-9) continue;
    if (!bins.empty() && std::find(bins.begin(), bins.end(), k) == bins.end()) continue;
    out.frequency_hz.push_back(f);
    const double g_ru = coherence(s, k, kDemand, kCommand);
    out.command_coherence.push_back(g_ru);
    command_noise.push_back((1.0 - g_ru) * s.power(k, kCommand));
    command_psd.push_back(s.power(k, kCommand));
    for (std::size_t c = 0; c < r.responses.size(); ++c) {
      const int y = kCommand + 1 + static_cast<int>(c);
      const double g_ry = coherence(s, k, kDemand, y);
      out.closed_loop[c].value.push_back(s.at(k, kDemand, y) / s.power(k, kDemand));
      out.closed_loop[c].coherence.push_back(g_ry);
      out.plant[c].value.push_back(s.at(k, kDemand, y) / s.at(k, kDemand, kCommand));
      out.plant[c].coherence.push_back(std::min(g_ry, g_ru));
      out.noise_floor[out.responses[c].name].push_back((1.0 - g_ry) * s.power(k, y));
      out.response_psd[out.responses[c].name].push_back(s.power(k, y));
      if (!bins.empty()) out.distortion[out.responses[c].name].push_back(power_beside(s, bins, k, y) / s.power(k, y));
    }
  }
  if (out.frequency_hz.empty()) throw std::invalid_argument("no frequency bin inside the band");
  out.estimation.averages = s.averages;
}

}  // namespace rigctl
