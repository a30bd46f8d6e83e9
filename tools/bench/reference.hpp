// Tight-tolerance reference solutions of the simulated plants, for
// `rigctl bench`'s plant section: Boost.Odeint's adaptive Dormand-Prince 5(4)
// at a given tolerance (1e-10 in the bench), driven by the same held
// commands as the plant's fixed-step RK4, with the plants' mode switches
// (bearing stick/slip, load stick/slip and hysteresis re-anchoring) located
// to ~1e-13 s by bisection instead of at sub-step ends.
//
// The right-hand sides are the plants' own (their public derivatives() and
// stick/slip pieces): the reference integrates the same equations, hidden
// effects and fault hooks included. What is the reference's own is the event
// handling and the composition of a step; rhs_agreement_*() checks that by
// stepping both from the same states with one RK4 step and reporting the
// largest relative difference (about 1e-13 when they agree); the bench prints
// it beside every error figure.
//
// This is the only file that includes Boost.Odeint (heavy to compile).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "plant/half_car/half_car_params.hpp"
#include "plant/half_car/half_car_plant.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_plant.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"

namespace rigctl::bench {

// Commands held over each control period (zero-order hold), in the plant's
// commands() order; unused entries are 0.
using HeldCommand = std::array<double, 2>;
using CommandSeries = std::vector<HeldCommand>;

struct ReferenceStats {
  double tolerance = 0.0;       // absolute and relative
  double wall_s = 0.0;          // integration only
  int64_t steps = 0;            // accepted steps
  int64_t rejected = 0;         // rejected step attempts
  int64_t rhs_evaluations = 0;
  int64_t events = 0;           // located mode switches
};

struct ReferenceResult {
  std::vector<std::string> names;         // state components, as state_vector() orders them
  std::vector<std::vector<double>> at;    // state at the end of each period
  ReferenceStats stats;
  bool completed = false;                 // false: stopped early (stop flag)
};

// State vectors in one order for the plant and its reference.
std::vector<std::string> quarter_car_state_names();
std::vector<double> state_vector(const QuarterCarState& s);
std::vector<std::string> pneumatic_state_names();
std::vector<double> state_vector(const PneumaticRotaryState& s);
std::vector<std::string> half_car_state_names();
std::vector<double> state_vector(const HalfCarState& s);

// From the plant's reset() state, for u.size() periods of period_s.
ReferenceResult reference_quarter_car(const QuarterCarParams& p, const CommandSeries& u, double period_s,
                                      double tolerance, const std::atomic<bool>& stop);
ReferenceResult reference_pneumatic(const PneumaticRotaryParams& p, const CommandSeries& u, double period_s,
                                    double tolerance, const std::atomic<bool>& stop);
ReferenceResult reference_half_car(const HalfCarParams& p, const CommandSeries& u, double period_s,
                                   double tolerance, const std::atomic<bool>& stop);

// Largest relative difference between one RK4 step of size h taken by the
// plant (one sub-step) and by this file's right-hand side, from each state
// with its command; states where the plant switched mode inside the step
// are left out. `checked` returns how many states were compared.
double rhs_agreement_quarter_car(const QuarterCarParams& p, const std::vector<QuarterCarState>& states,
                                 const std::vector<HeldCommand>& u, double h, int& checked);
double rhs_agreement_pneumatic(const PneumaticRotaryParams& p, const std::vector<PneumaticRotaryState>& states,
                               const std::vector<HeldCommand>& u, double h, int& checked);
double rhs_agreement_half_car(const HalfCarParams& p, const std::vector<HalfCarState>& states,
                              const std::vector<HeldCommand>& u, double h, int& checked);

}  // namespace rigctl::bench
