// A feedback controller run once per tick. Implementations are allocation
// free in update(); their term names are fixed at construction.
#pragma once

#include <string>
#include <vector>

#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

// What a controller's ControllerTerms hold each tick (the run log's
// controller columns, the telemetry's controller message):
//   setpoint            the demand update() was given (the loop's, after its shaper)
//   measurement         the fed-back quantity that demand is compared with
//                       (the half car's controllers: the body heave z_s)
//   error               setpoint - measurement, always
//   term[i]             the controller's own parts, named by term_names()[i]
//                       (entries past term_names() are not published)
//   output_unsaturated  the first output before its limit
//   output              the first output as commanded
//   saturated           any output was limited this tick (not only the first)
//   integrator_held     the integrator did not integrate this tick (anti-windup,
//                       or the actuator not following); false without one
// Every controller fills all but term[] through fill_terms, so these
// meanings are kept in one place; term[] it writes itself.
struct ControllerOutcome {
  double setpoint = 0.0;
  double measurement = 0.0;
  double unsaturated = 0.0;  // the first output before its limit
  double output = 0.0;       // the first output as commanded
  bool saturated = false;    // any output limited
  bool integrator_held = false;
};

inline void fill_terms(ControllerTerms& terms, const ControllerOutcome& o) noexcept {
  terms.setpoint = o.setpoint;
  terms.measurement = o.measurement;
  terms.error = o.setpoint - o.measurement;
  terms.output_unsaturated = o.unsaturated;
  terms.output = o.output;
  terms.saturated = o.saturated;
  terms.integrator_held = o.integrator_held;
}

class Controller {
 public:
  virtual ~Controller() = default;
  virtual const std::string& name() const = 0;
  // Names of ControllerTerms::term entries, e.g. {"p", "i"}.
  virtual const std::vector<std::string>& term_names() const = 0;
  virtual void reset() noexcept = 0;
  // Computes the command for this tick from the setpoint and the sample and
  // fills terms (what they hold: above).
  virtual void update(double setpoint, const Sample& sample, Command& command,
                      ControllerTerms& terms) noexcept = 0;
};

}  // namespace rigctl
