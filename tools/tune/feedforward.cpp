#include "tools/tune/feedforward.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tools/tune/plant_grid.hpp"

namespace rigctl {

namespace {

// A plant whose phase is this far from -90 deg is not an integrator there:
// |G| w is then no speed per command. 30 deg takes the quarter car's valve
// lag and load dynamics below its crossover (-78 to -102 deg).
constexpr double kIntegratorPhaseToleranceDeg = 30.0;

FeedforwardDesign none(std::string why) {
  FeedforwardDesign d;
  d.reason_for_none = std::move(why);
  return d;
}

}  // namespace

FeedforwardDesign design_feedforward(const PlantResponse& plant, double crossover_hz, const RigConfig& config) {
  if (config.controller.type != ControllerKind::kPi) return none("only the PI has a demand feedforward");
  if (config.profile.type == ProfileKind::kRampSteps && config.profile.filter_tau_s == 0.0) {
    return none("the standard step is unfiltered (profile.filter_tau_s 0): its demand has no speed to feed forward");
  }
  if (!std::isfinite(crossover_hz)) return none("the design has no crossover in the measured band");
  FeedforwardDesign d;
  d.band_low_hz = crossover_hz / 2.0;
  d.band_high_hz = crossover_hz;
  std::vector<double> speed_gain;
  for (std::size_t i = 0; i < plant.frequency_hz.size(); ++i) {
    const double f = plant.frequency_hz[i];
    if (f < d.band_low_hz || f > d.band_high_hz || plant.coherence[i] < kDesignCoherence) continue;
    const double phase_deg = std::arg(plant.position[i]) * 180.0 / std::numbers::pi;
    if (std::abs(phase_deg + 90.0) > kIntegratorPhaseToleranceDeg) {
      return none("the plant's phase at " + std::to_string(f) + " Hz is not an integrator's: no velocity gain to invert");
    }
    speed_gain.push_back(std::abs(plant.position[i]) * 2.0 * std::numbers::pi * f);
  }
  if (speed_gain.empty()) return none("no coherent line of the measured plant in the octave below the crossover");
  std::sort(speed_gain.begin(), speed_gain.end());
  const std::size_t n = speed_gain.size();
  d.velocity_gain = 0.5 * (speed_gain[(n - 1) / 2] + speed_gain[n / 2]);  // the median
  d.kff = 1.0 / d.velocity_gain;
  return d;
}

}  // namespace rigctl
