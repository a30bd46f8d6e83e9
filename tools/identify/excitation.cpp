#include "tools/identify/excitation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace rigctl {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

void check(const ExcitationSpec& s) {
  const double nyquist = 0.5 / s.period_s;
  if (!(s.period_s > 0.0)) throw std::invalid_argument("excitation: control period must be positive");
  if (!(s.band_min_hz > 0.0 && s.band_min_hz < s.band_max_hz && s.band_max_hz < nyquist)) {
    throw std::invalid_argument("excitation band [" + std::to_string(s.band_min_hz) + ", " +
                                std::to_string(s.band_max_hz) + "] Hz must lie inside (0, " + std::to_string(nyquist) +
                                ") Hz, the low end first");
  }
  if (!(s.resolution_hz > 0.0 && s.resolution_hz <= s.band_min_hz)) {
    throw std::invalid_argument("excitation resolution must be positive and at most the band's low end");
  }
  if (!(std::isfinite(s.amplitude) && s.amplitude >= 0.0)) throw std::invalid_argument("excitation amplitude must be finite and >= 0");
  if (!(s.duration_s * s.resolution_hz >= 2.0)) {
    throw std::invalid_argument("excitation duration must hold at least two segments (2 / resolution_hz)");
  }
}

// The bins k of a segment of n ticks whose frequency k / (n T) is in the band.
std::pair<std::size_t, std::size_t> band_bins(const ExcitationSpec& s, std::size_t n) {
  const double df = 1.0 / (static_cast<double>(n) * s.period_s);
  const auto lo = static_cast<std::size_t>(std::ceil(s.band_min_hz / df - 1e-9));
  const auto hi = static_cast<std::size_t>(std::floor(s.band_max_hz / df + 1e-9));
  return {std::max<std::size_t>(lo, 1), hi};
}

// A random-odd grid: the odd bins of the band, one in each group of three
// left out at random (never the band's first, which sets its low end). The
// rig's even-order distortion falls on the even bins, its odd-order
// distortion (friction, hysteresis) partly on the odd bins left out: both
// are seen beside the lines, where noise alone would put much less.
std::vector<std::size_t> random_odd_lines(const ExcitationSpec& s, std::size_t n) {
  const auto [lo, hi] = band_bins(s, n);
  std::vector<std::size_t> odd;
  for (std::size_t k = lo | 1U; k <= hi; k += 2) odd.push_back(k);
  std::mt19937_64 rng(s.seed);
  std::vector<std::size_t> out;
  for (std::size_t g = 0; g < odd.size(); g += 3) {
    const std::size_t size = std::min<std::size_t>(3, odd.size() - g);
    // The first group keeps its first bin; a group of one keeps it.
    const std::size_t first = g == 0 ? 1 : 0;
    const std::size_t skip = size > first + 1 ? first + rng() % (size - first) : size;
    for (std::size_t i = 0; i < size; ++i) {
      if (i != skip) out.push_back(odd[g + i]);
    }
  }
  return out;
}

// Schroeder phases: a low crest factor for equal lines (about 1.7).
std::vector<double> multisine_period(const std::vector<std::size_t>& lines, std::size_t n) {
  const double count = static_cast<double>(lines.size());
  std::vector<double> x(n, 0.0);
  for (std::size_t m_index = 0; m_index < lines.size(); ++m_index) {
    const std::size_t k = lines[m_index];
    const double m = static_cast<double>(m_index);
    const double phase = -std::numbers::pi * m * (m + 1.0) / count;
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += std::cos(kTwoPi * static_cast<double>(k * i % n) / static_cast<double>(n) + phase);
    }
  }
  return x;
}

// A linear sweep from the band's low to its high end over one segment.
std::vector<double> chirp_period(const ExcitationSpec& s, std::size_t n) {
  const double length = static_cast<double>(n) * s.period_s;
  const double rate = (s.band_max_hz - s.band_min_hz) / length;
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * s.period_s;
    x[i] = std::sin(kTwoPi * (s.band_min_hz * t + 0.5 * rate * t * t));
  }
  return x;
}

// Random phases, amplitude 1/sqrt(f) (power 1/f) on every bin of the whole
// record inside the band: Gaussian-like band-limited pink noise.
std::vector<double> pink_noise(const ExcitationSpec& s, std::size_t n) {
  const auto [lo, hi] = band_bins(s, n);
  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> phase(0.0, kTwoPi);
  std::vector<double> x(n, 0.0);
  const double df = 1.0 / (static_cast<double>(n) * s.period_s);
  for (std::size_t k = lo; k <= hi; ++k) {
    const double a = 1.0 / std::sqrt(static_cast<double>(k) * df);
    const double p = phase(rng);
    const double w = kTwoPi * static_cast<double>(k) / static_cast<double>(n);
    // cos(w i + p) by rotation: exact enough over a record and cheap.
    const double c = std::cos(w), sn = std::sin(w);
    double re = std::cos(p), im = std::sin(p);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += a * re;
      const double next = re * c - im * sn;
      im = re * sn + im * c;
      re = next;
    }
  }
  return x;
}

void scale_to_peak(std::vector<double>& x, double amplitude) {
  double peak = 0.0;
  for (double v : x) peak = std::max(peak, std::abs(v));
  const double g = peak > 0.0 ? amplitude / peak : 0.0;
  for (double& v : x) v *= g;
}

}  // namespace

std::size_t segment_ticks(double resolution_hz, double period_s) {
  return static_cast<std::size_t>(std::llround(1.0 / (resolution_hz * period_s)));
}

Excitation make_excitation(const ExcitationSpec& s) {
  check(s);
  Excitation e;
  e.segment_ticks = segment_ticks(s.resolution_hz, s.period_s);
  const auto segments = static_cast<std::size_t>(std::floor(s.duration_s * s.resolution_hz + 1e-9));
  switch (s.kind) {
    case ExcitationKind::kMultisine:
    case ExcitationKind::kChirp: {
      e.periodic = true;
      if (s.kind == ExcitationKind::kMultisine) e.lines = random_odd_lines(s, e.segment_ticks);
      if (s.kind == ExcitationKind::kMultisine && e.lines.empty()) {
        throw std::invalid_argument("excitation band holds no odd bin at resolution " + std::to_string(s.resolution_hz) + " Hz");
      }
      const auto one = s.kind == ExcitationKind::kMultisine ? multisine_period(e.lines, e.segment_ticks)
                                                            : chirp_period(s, e.segment_ticks);
      e.values.reserve(segments * e.segment_ticks);
      for (std::size_t k = 0; k < segments; ++k) e.values.insert(e.values.end(), one.begin(), one.end());
      break;
    }
    case ExcitationKind::kPinkNoise:
      e.values = pink_noise(s, static_cast<std::size_t>(std::floor(s.duration_s / s.period_s + 1e-9)));
      break;
  }
  scale_to_peak(e.values, s.amplitude);
  return e;
}

}  // namespace rigctl
