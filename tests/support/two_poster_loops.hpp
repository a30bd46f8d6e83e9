// The simulated two-poster rig closed by two of the rig's own PI
// controllers (rt/control/pi_controller.hpp), one per post, each from its
// own rod position to its own valve, with the quarter car's gains
// (config/quarter_car.yaml: kp 80 /m, ki 60 /(m s)), one 2.5 ms period per
// step, as the rig loop would run them with two control channels (which it
// does not yet: this is the tests' stand-in). Plays demand records and
// returns the chosen response records.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "plant/two_poster/two_poster_plant.hpp"
#include "rt/control/pi_controller.hpp"

namespace rigctl::test {

struct TwoPosterLoops {
  double period_s = 0.0025;

  using Pick = std::function<std::vector<double>(const std::array<double, two_poster_signal::kCount>&)>;

  std::vector<std::vector<double>> play(TwoPosterPlant& plant, const std::vector<std::vector<double>>& demands,
                                        const Pick& pick) const {
    plant.reset();
    std::array<PiController, 2> pi{controller(0), controller(1)};
    Sample sample;
    Command command;
    ControllerTerms terms;
    std::vector<std::vector<double>> out;
    for (std::size_t i = 0; i < demands.front().size(); ++i) {
      std::array<double, two_poster_signal::kCount> y{};
      plant.measure(y);
      std::copy(y.begin(), y.end(), sample.value.begin());
      const auto picked = pick(y);
      if (out.empty()) out.resize(picked.size());
      for (std::size_t j = 0; j < picked.size(); ++j) out[j].push_back(picked[j]);
      for (std::size_t p = 0; p < 2; ++p) pi[p].update(demands[p][i], sample, command, terms);
      plant.advance(std::span<const double>(command.value.data(), 2), period_s);
    }
    return out;
  }

 private:
  PiController controller(int post) const {
    PiConfig c;  // kp 80, ki 60: the quarter car's
    c.period_s = period_s;
    c.feedback_input = static_cast<int>(post == 0 ? two_poster_signal::kZr1 : two_poster_signal::kZr2);
    c.output_index = post;
    return PiController(c);
  }
};

}  // namespace rigctl::test
