#include "plant/servo_valve.hpp"

#include <algorithm>
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

double overlapped_spool(double x, double overlap, double r) {
  if (overlap <= 0.0) return x;
  const double a = std::abs(x);
  double open;
  if (r <= 0.0) {
    open = std::max(0.0, a - overlap);
  } else if (a <= overlap - r) {
    open = 0.0;
  } else if (a >= overlap + r) {
    open = a - overlap;
  } else {
    const double s = a - overlap + r;  // 0 .. 2r
    open = s * s / (4.0 * r);
  }
  return std::copysign(open, x);
}

}  // namespace rigctl
