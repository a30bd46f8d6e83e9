// Force and flow laws of the quarter car's optional (hidden) effects
// (QuarterCarHiddenEffects), each in more than one physical form so that the
// hidden-effect generator (tools/hidden_effects/quarter_car.cpp) can make a
// run whose effect is not the diagnosis candidate's formula. Pure functions;
// the plant holds the one extra state (the LuGre bristle deflection).
#pragma once

#include "plant/quarter_car/quarter_car_params.hpp"

namespace rigctl {

// Rod seal friction [N], opposing v_r. Form 0: Simscape "Cylinder Friction"
// (Stribeck peak sqrt(2e)(F_brk - F_c)..., Coulomb tanh(v / v_coul)); form 1:
// an exponential Stribeck decay exp(-|v| / v_brk) on a steep Coulomb step
// (tanh over 1 mm/s).
double seal_friction_force(const QuarterCarHiddenEffects& h, double v_r, double p1, double p2);

// Effective bulk modulus of oil with free air (Simscape mixture law) at gauge
// pressure p, air fraction alpha at atmosphere, polytropic index n (1
// isothermal, 1.4 adiabatic compression of the bubbles).
double mixture_bulk_modulus(double beta_liquid, double alpha, double n, double p);

// Damper force [N] with asymmetric coefficients: piecewise linear, times
// (1 + |v| progression) on rebound strokes (a progressive valve), v = v_w - v_b.
double damper_force(double bd, const QuarterCarHiddenEffects& h, double v_rel);

// LuGre bristle model (Canudas de Wit et al. 1995): g(v) = F_c + (F_brk - F_c)
// exp(-(v/v_s)^2); dz/dt = v - sigma0 |v| z / g(v); F = sigma0 z + sigma1 dz/dt + D v.
struct LugreLevels {
  double coulomb, breakaway, stribeck_velocity, viscous, sigma0, sigma1;
};
double lugre_force(const LugreLevels& l, double z, double v);
// Exact bristle update over a step h at constant velocity v.
double lugre_advance(const LugreLevels& l, double z, double v, double h);

}  // namespace rigctl
