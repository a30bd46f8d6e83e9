// Two PI position loops around the simulated two-poster rig, written in the
// test (the rig loop runs one channel today): each post's valve command
// from its own rod position, the quarter car's gains (config/quarter_car.yaml:
// kp 80 /m, ki 60 /(m s)) and its rest command as the integrator's start,
// one 2.5 ms period per step. Plays demand records and returns the chosen
// response records.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "plant/two_poster/two_poster_plant.hpp"

namespace rigctl::test {

struct TwoPosterLoops {
  double kp = 80.0, ki = 60.0, period_s = 0.0025;

  // responses(measured signals) -> the values recorded each tick.
  using Pick = std::function<std::vector<double>(const std::array<double, two_poster_signal::kCount>&)>;

  std::vector<std::vector<double>> play(TwoPosterPlant& plant, const std::vector<std::vector<double>>& demands,
                                        const Pick& pick) const {
    plant.reset();
    std::array<double, 2> integral{plant.rest_command(0) / ki, plant.rest_command(1) / ki};
    std::array<double, two_poster_signal::kCount> y{};
    std::vector<std::vector<double>> out;
    for (std::size_t i = 0; i < demands.front().size(); ++i) {
      plant.measure(y);
      const auto picked = pick(y);
      if (out.empty()) out.resize(picked.size());
      for (std::size_t j = 0; j < picked.size(); ++j) out[j].push_back(picked[j]);
      std::array<double, 2> u{};
      for (std::size_t p = 0; p < 2; ++p) {
        const double e = demands[p][i] - y[p == 0 ? two_poster_signal::kZr1 : two_poster_signal::kZr2];
        integral[p] += e * period_s;
        u[p] = kp * e + ki * integral[p];
      }
      plant.advance(u, period_s);
    }
    return out;
  }
};

}  // namespace rigctl::test
