// A feedback controller run once per tick. Implementations are allocation
// free in update(); their term names are fixed at construction.
#pragma once

#include <string>
#include <vector>

#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

class Controller {
 public:
  virtual ~Controller() = default;
  virtual const std::string& name() const = 0;
  // Names of ControllerTerms::term entries, e.g. {"p", "i"}.
  virtual const std::vector<std::string>& term_names() const = 0;
  virtual void reset() noexcept = 0;
  // Computes the command for this tick from the setpoint and the sample.
  virtual void update(double setpoint, const Sample& sample, Command& command,
                      ControllerTerms& terms) noexcept = 0;
};

}  // namespace rigctl
