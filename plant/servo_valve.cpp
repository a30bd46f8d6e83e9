#include "plant/servo_valve.hpp"

#include <cmath>

namespace rigctl {

double orifice_root(double p, double laminar_pressure) {
  if (std::abs(p) < laminar_pressure) return p / std::sqrt(laminar_pressure);
  return std::copysign(std::sqrt(std::abs(p)), p);
}

ValveFlows valve_flows(double spool, double p1, double p2, double flow_gain,
                       double supply_pressure, double laminar_pressure) {
  ValveFlows q;
  const double k = flow_gain * spool;
  if (spool >= 0.0) {
    q.q1 = k * orifice_root(supply_pressure - p1, laminar_pressure);
    q.q2 = k * orifice_root(p2, laminar_pressure);
  } else {
    q.q2 = k * orifice_root(supply_pressure - p2, laminar_pressure);
    q.q1 = k * orifice_root(p1, laminar_pressure);
  }
  return q;
}

}  // namespace rigctl
