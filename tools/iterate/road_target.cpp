#include "tools/iterate/road_target.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <stdexcept>

#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

// Integration sub-steps per target sample: the wheel hop (about 24 Hz)
// and the tyre's damping are resolved by RK4 at 0.25 ms with a wide margin.
constexpr int kSubsteps = 10;

using State = std::array<double, 4>;  // x_w, v_w, x_b, v_b

State derivative(const QuarterCarParams& p, const State& s, RoadSample road) {
  const double tyre = p.tyre_stiffness * (road.z - s[0]) + p.tyre_damping * (road.dz - s[1]);
  const double suspension = p.spring_stiffness * (s[0] - s[2]) + p.damper_damping * (s[1] - s[3]);
  return {s[1], (tyre - suspension) / p.mass_wheel, s[3], suspension / p.mass_body};
}

State rk4(const QuarterCarParams& p, const State& s, const RoadProfile& road, double t, double h) {
  auto add = [](const State& a, const State& b, double k) {
    State r;
    for (std::size_t i = 0; i < 4; ++i) r[i] = a[i] + k * b[i];
    return r;
  };
  const State k1 = derivative(p, s, road.at(0, t));
  const State k2 = derivative(p, add(s, k1, h / 2), road.at(0, t + h / 2));
  const State k3 = derivative(p, add(s, k2, h / 2), road.at(0, t + h / 2));
  const State k4 = derivative(p, add(s, k3, h), road.at(0, t + h));
  State r;
  for (std::size_t i = 0; i < 4; ++i) r[i] = s[i] + h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  return r;
}

void check(const RoadTargetSpec& s) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0)) throw std::invalid_argument(std::string("road target: ") + name + " must be positive");
  };
  positive(s.speed_m_s, "speed");
  positive(s.duration_s, "duration");
  positive(s.period_s, "period");
  if (!(s.band_max_hz > s.band_min_hz) || s.band_min_hz < 0.0) throw std::invalid_argument("road target: band must be 0 <= low < high");
  if (s.fade_s < 0.0 || 2.0 * s.fade_s >= s.duration_s) throw std::invalid_argument("road target: fade must be under half the duration");
}

}  // namespace

void fade_ends(std::vector<double>& x, std::size_t fade) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < fade && i < n; ++i) {
    const double w = 0.5 - 0.5 * std::cos(std::numbers::pi * static_cast<double>(i) / static_cast<double>(fade));
    x[i] *= w;
    x[n - 1 - i] *= w;
  }
}

RoadTarget make_road_target(const QuarterCarParams& vehicle, const RoadTargetSpec& spec) {
  check(spec);
  RoadProfileSpec road_spec;
  road_spec.kind = RoadKind::kIso8608;
  road_spec.iso.road_class = spec.road_class;
  road_spec.iso.seed = spec.seed;
  const RoadProfile road(road_spec, spec.speed_m_s, WheelArrangement::kInLine, 0.0);
  const auto n = static_cast<std::size_t>(std::llround(spec.duration_s / spec.period_s));
  const auto lead = static_cast<std::size_t>(std::llround(spec.lead_s / spec.period_s));
  const double h = spec.period_s / kSubsteps;
  State s{};
  RoadTarget out;
  for (std::size_t i = 0; i < lead + n; ++i) {
    const double t = static_cast<double>(i) * spec.period_s;
    if (i >= lead) {
      out.t.push_back(static_cast<double>(i - lead) * spec.period_s);
      out.road.push_back(road.height(0, t));
      out.wheel.push_back(s[0]);
    }
    for (int k = 0; k < kSubsteps; ++k) s = rk4(vehicle, s, road, t + k * h, h);
  }
  const auto fade = static_cast<std::size_t>(std::llround(spec.fade_s / spec.period_s));
  for (auto* x : {&out.road, &out.wheel}) {
    *x = band_limited(*x, spec.period_s, spec.band_min_hz, spec.band_max_hz);
    fade_ends(*x, fade);
    for (double& v : *x) v += spec.offset;
  }
  return out;
}

void write_road_target(const RoadTarget& target, const RoadTargetSpec& spec, const std::string& channel,
                       const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  const char* classes = "ABCDE";
  f << "# rig: quarter_car\n"
    << "# source: rigctl road-target: wheel displacement of a quarter car over an ISO 8608 class "
    << classes[static_cast<int>(spec.road_class)] << " road\n"
    << "# road_speed_m_s: " << spec.speed_m_s << "\n# road_seed: " << spec.seed << "\n"
    << "# band_hz: " << spec.band_min_hz << " " << spec.band_max_hz << "\n"
    << "t," << channel << ",road\n"
    << std::setprecision(9);
  for (std::size_t i = 0; i < target.t.size(); ++i) f << target.t[i] << "," << target.wheel[i] << "," << target.road[i] << "\n";
  if (!f) throw std::runtime_error("write failed: " + path);
}

}  // namespace rigctl
