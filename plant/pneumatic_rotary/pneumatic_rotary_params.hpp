// Parameters of the flexible-bladder rotary pneumatic servo of seed paper 002
// (Tillett et al.), in SI. Defaults are docs/rig-models.md section 2,
// which resolves the paper's unit slips; reasons are noted beside each value
// that was derived or chosen.
#pragma once

namespace rigctl {

// Bladder-distortion hysteresis, the modified trapezoid of Fig. 2b: on a
// reversal the torque changes stepwise, then linearly with angle up to the
// hysteresis boundary, then stays saturated. Independent of speed.
struct BladderHysteresisParams {
  bool enabled = true;
  double level = 0.02;            // half-width as a fraction of max torque (+-2 % = +-1.5 N m)
  double step_fraction = 0.5;     // part of the full 2x level swing taken stepwise at a reversal
  double boundary_angle = 0.035;  // [rad] angle travelled after a reversal to reach the boundary
};

// Pure Coulomb friction of the caliper brake (Fig. 2d).
struct CoulombBrakeParams {
  bool enabled = false;
  double level = 0.0;  // as a fraction of max torque (the paper uses 2, 6, 8, 10 %)
};

// Second physical forms of the effects, for the hidden-effect generator
// (tools/hidden_effects/pneumatic_rotary.cpp): each differs in shape from
// both the plant's first form and the diagnosis candidate. All off by default.
struct PneumaticHiddenForms {
  // Loop-shaped (Bouc-Wen) bladder hysteresis: torque H z with
  // dz/dtheta = (1 - (0.5 sign(omega z) + 0.5) |z|^n) / angle; after a
  // reversal z ramps linearly, then bends smoothly into saturation at 1.
  double bouc_wen_level = 0.0;       // H as a fraction of max torque; 0: off
  double bouc_wen_angle = 0.02;      // [rad] initial slope angle (H / angle N m/rad)
  double bouc_wen_exponent = 1.5;    // n: the sharpness of the bend
  // Smooth (Simscape rotational) friction: Stribeck peak ratio 1.3 at
  // 0.02 rad/s, Coulomb tanh over 4 mrad/s; no stick/slip state.
  double smooth_friction_level = 0.0;  // Coulomb level as a fraction of max torque; 0: off
  // Heat transfer: the exponent goes from n_slow at rest to gamma at speed,
  // n = n_slow + (gamma - n_slow) |omega| / (|omega| + corner).
  double polytropic_slow = 0.0;        // n at rest; 0: off (constant gamma)
  double polytropic_corner_speed = 0.3;  // [rad/s]
  // Mechanical null shift of the spool [m] after the dither (the electrical
  // form is valve_null_offset [V] before it): the spool limit is reached
  // sooner on one side.
  double spool_null_shift = 0.0;
  // Rounded metering edges of the overlapped spool [m]; 0: sharp lands.
  double overlap_edge_radius = 0.0;
};

struct PneumaticRotaryParams {
  // Valve: spool proportional to solenoid voltage via offset, gain, saturation.
  double solenoid_gain = 0.161e-3;    // [m/V]: +-5 V gives +-0.81 mm
  double spool_limit = 0.81e-3;       // [m]
  double valve_null_offset = 0.0;     // [V] added to the command before the gain
  // Spool overlap [m]: the lands still cover the ports for |x| below it, so
  // the flow follows the opening sign(x) max(|x| - overlap, 0), a sharp dead
  // band (Merritt; overlap > 0 is the "dead zone about null" of the cause id
  // valve_deadband). 0: a critically lapped spool, as the paper assumes.
  double valve_overlap = 0.0;
  double flow_gain = 1.5;             // C1 [kg/(s m)] per metre of spool travel (paper's "1.5/kg m" slip)
  double flow_pressure_coefficient = 4e-9;  // C2 [kg/(s Pa)] (paper's "0.4e-8 ms")
  bool dither = true;
  double dither_amplitude = 1.5;      // [V] peak: 30 % of the +-5 V range peak-to-peak
  double dither_frequency = 50.0;     // [Hz]

  // Chambers (Shearer, linearised about mid-stroke).
  double chamber_volume = 0.25e-3;      // V [m^3] per bladder incl. lines, chosen
  double quiescent_pressure = 4.5e5;    // Pq [Pa abs], chosen (supply ~7 bar abs)
  double supply_temperature = 293.0;    // T_s [K]
  double heat_capacity_ratio = 1.4;     // gamma: adiabatic
  double gas_constant = 287.0;          // R [J/(kg K)]

  // Actuator and load.
  double first_moment = 1.2e-4;  // alpha [m^3/rad]: max torque 75 N m at 6.25 bar differential
  double inertia = 1.7;          // I [kg m^2]: payload 1.7 or 0.4
  double max_torque = 75.0;      // [N m] reference for the per-cent levels (alpha x 6.25 bar)
  double angle_limit = 1.0;      // [rad] travel each side of mid-stroke before the end stops
  double end_stop_stiffness = 5e3;   // [N m/rad]
  double end_stop_damping = 50.0;    // [N m s/rad]

  BladderHysteresisParams hysteresis;
  CoulombBrakeParams brake;
  PneumaticHiddenForms forms;

  // RK4 sub-steps per control period: 0.25 ms at 2.5 ms, set by the 50 Hz dither.
  int substeps = 10;
};

}  // namespace rigctl
