// Parameters of the quarter-car road-simulator rig of seed paper 000, in SI.
// Defaults are the nominal set of docs/rig-models.md section 1, where
// the seed's unit slips are resolved; the reasons are repeated next to each
// value that was derived or chosen rather than taken from the paper.
#pragma once

namespace rigctl {

struct BearingFrictionParams {
  bool enabled = false;
  double coulomb_base = 40.0;        // F_c0 [N]
  double normal_coefficient = 0.05;  // mu [1]: Coulomb part grows with the bearing normal force
  bool normal_force_dependent = true;
  double stiction_excess = 100.0;    // dF_s [N]: breakaway = F_c + dF_s (about 200 N = ks * 6.9 mm, the paper's stick limit)
  double stribeck_velocity = 0.015;  // v_s [m/s]
  double stribeck_exponent = 2.0;    // delta [1]
  double viscous = 200.0;            // D [N s/m]
  double construction_angle = 1.0821;  // theta [rad] = 62 deg, chosen (paper gives none)
  double damper_free_length = 0.342;   // L_d [m], paper
};

// Physics the nominal model (and the diagnosis baseline) leaves out, for the
// hidden-effect generator (tools/hidden_effects/quarter_car.cpp). All off by default.
// Each is written in a form the diagnosis does not fit (its candidates are
// smoother or simpler), so that finding them tests the physics, not a formula.
struct QuarterCarHiddenEffects {
  // Actuator seal friction on the rod, Simscape "Cylinder Friction" style:
  // Coulomb level F_pr + f_c (p1 + p2), a Stribeck peak and viscous term,
  // F = sqrt(2e)(Fbrk - Fc) exp(-(v/v_st)^2) v/v_st + Fc tanh(v/v_coul) + f v.
  double seal_preload = 0.0;              // F_pr [N]
  double seal_pressure_coefficient = 0.0; // f_c [N/Pa]
  double seal_breakaway_ratio = 1.3;      // F_brk / F_c [1]
  double seal_breakaway_velocity = 0.02;  // v_brk [m/s]; v_st = v_brk sqrt(2), v_coul = v_brk / 2
  double seal_viscous = 0.0;              // f [N s/m]
  int seal_form = 0;                      // 0 Simscape cylinder friction, 1 exponential Stribeck on a steep step
  // LuGre bristle friction on the body bearings (the levels of
  // BearingFrictionParams, which then stays disabled): the second physical
  // form of bearing friction beside the Karnopp stick/slip element.
  bool bearing_lugre = false;
  double lugre_sigma0 = 1e5;              // bristle stiffness [N/m]: 2 mm of presliding at 200 N
  double lugre_sigma1 = 500.0;            // bristle damping [N s/m], about 0.05 x critical with the body
  // Extra laminar cross-port conductance beside the worn-seal orifice (the
  // laminar-plus-turbulent leak) [m^3/(s Pa)].
  double extra_laminar_leak = 0.0;
  // A worn piston seal: turbulent cross-port flow K sign(dp) sqrt|dp|
  // (laminar below the valve's laminar pressure), beside the nominal laminar leak.
  double worn_seal_orifice = 0.0;         // K [m^3/s/sqrt(Pa)]
  // Spool overlap: no metering until |x_s| exceeds it, a sharp dead band.
  double valve_overlap = 0.0;             // [fraction of rated spool travel]
  double valve_overlap_edge_radius = 0.0; // [fraction] 0: sharp lands; > 0 rounded metering edges
  // Entrained air: effective bulk modulus of oil with free air, Simscape
  // isothermal-liquid mixture law (docs/rig-models.md 1.6), n = 1.
  double air_fraction = 0.0;              // alpha at atmospheric pressure [1]
  double air_polytropic_index = 1.0;      // n of the bubbles: 1 isothermal, 1.4 adiabatic
  // Damper with different rebound and compression coefficients (piecewise
  // linear in the relative velocity). 1, 1: the nominal symmetric damper.
  double damper_compression_factor = 1.0; // v_w - v_b > 0
  double damper_rebound_factor = 1.0;     // v_w - v_b < 0
  double damper_rebound_progression = 0.0;  // [s/m] rebound force x (1 + this |v|): a progressive valve
  // The tyre cannot pull: contact force max(0, F). 0 keeps the nominal
  // bilateral tyre; 1 is a real contact; between, that part of a pull is lost.
  double tyre_pull_loss = 0.0;
  // Tyre damping only while the tyre touches (a tyre that leaves the plate
  // keeps no damper), the second form of lift-off.
  bool tyre_damping_in_contact_only = false;
};

struct QuarterCarParams {
  // Hydraulic actuator and servovalve.
  double area_cap = 1.96e-3;       // A1 [m^2]
  double area_rod = 0.94e-3;       // A2 [m^2]
  double bulk_modulus = 1.43e9;    // beta [Pa]
  double supply_pressure = 200e5;  // Ps [Pa gauge]; tank is 0
  // Kv [m^3/s/sqrt(Pa)] per unit command: 20 l/min at 35 bar per metering edge.
  // The paper's 0.99e-4 m^3/s/mA gives absurd flows (docs/rig-models.md 1.5.1).
  double valve_flow_gain = 1.782e-7;
  double valve_time_constant = 0.004;  // tau_r [s], chosen: the paper gives none
  double laminar_pressure = 2e5;       // [Pa] below it the orifice law is linear, keeping dP/dt Lipschitz
  double cavitation_pressure = -0.95e5;  // [Pa gauge] floor of chamber pressure
  bool leakage = true;
  double leakage_resistance = 2.45e11;  // R_l [Pa s/m^3]
  double dead_volume_cap = 30e-6;       // V1d [m^3], chosen
  double dead_volume_rod = 30e-6;       // V2d [m^3], chosen
  double stroke_min = -0.010;           // end cap position [m]; x_r = 0 is home
  double stroke_max = 0.170;            // head position [m]
  double end_stop_stiffness = 5e7;      // [N/m]
  double end_stop_damping = 2e4;        // [N s/m]

  // Masses and suspension.
  double mass_rod = 5.0;      // Mr [kg] actuator rod and tyre plate
  double mass_wheel = 40.0;   // Mw [kg]
  double mass_body = 240.0;   // Mb [kg]
  double rod_damping = 500.0; // Bvr [N s/m]
  double tyre_stiffness = 9.2e5;   // kt [N/m]
  double tyre_damping = 3886.0;    // bt [N s/m]
  double spring_stiffness = 2.89e4;  // ks [N/m]
  double damper_damping = 260.0;     // bd [N s/m]
  double gravity = 9.81;             // g [m/s^2]

  BearingFrictionParams bearing_friction;
  QuarterCarHiddenEffects hidden;

  // RK4 sub-steps per control period. 0: as few as the parameters' fastest
  // mode allows (quarter_car_step_size.hpp; 7 at 2.5 ms for the nominal rig);
  // a number: exactly that many.
  int substeps = 0;
};

}  // namespace rigctl
