// A physical model that a simulated driver can step in place of a rig.
#pragma once

#include <span>

#include "rt/sample.hpp"

namespace rigctl {

class SimulatedPlant {
 public:
  virtual ~SimulatedPlant() = default;

  // Noise-free signals the plant exposes, in SI units: first the quantities a
  // sensor on the real rig measures (named as in the run-file spec), then
  // simulator-only truth channels prefixed "sim_".
  virtual const std::vector<ChannelInfo>& signals() const = 0;
  // Actuator commands the plant takes, e.g. {"u", "1"}.
  virtual const std::vector<ChannelInfo>& commands() const = 0;

  // Back to the configured initial state.
  virtual void reset() = 0;

  // Advances by dt with the commands held constant (zero-order hold, as a DAC
  // does). Real-time path: no allocation.
  virtual void advance(std::span<const double> command, double dt) = 0;

  // Writes signals() in order. Real-time path.
  virtual void measure(std::span<double> out) const = 0;
};

}  // namespace rigctl
