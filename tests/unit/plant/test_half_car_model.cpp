// The 4-DOF half vehicle of seed 001: linear model (eq. 5) against the
// paper's equations and hand calculations, the simulator's static
// equilibrium, free response, bump timing (eq. 11), tyre lift-off, the roll
// moment of eqs. 6-8, and the ISO 8608 road.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <vector>

#include "plant/half_car/half_car_model.hpp"
#include "plant/half_car/half_car_plant.hpp"
#include "plant/half_car/road_profile.hpp"

using namespace rigctl;
namespace sig = half_car_signal;

namespace {

constexpr double kPi = std::numbers::pi;
double hz(double omega) { return omega / (2.0 * kPi); }
double series(double k, double kt) { return k * kt / (k + kt); }

using Signals = std::array<double, sig::kCount>;

std::vector<Signals> simulate(HalfCarPlant& plant, double duration, double dt, std::array<double, 2> force = {0, 0}) {
  std::vector<Signals> out;
  const auto n = static_cast<std::size_t>(std::lround(duration / dt));
  out.reserve(n + 1);
  Signals s;
  plant.measure(s);
  out.push_back(s);
  for (std::size_t k = 0; k < n; ++k) {
    plant.advance(force, dt);
    plant.measure(s);
    out.push_back(s);
  }
  return out;
}

// Frequency [Hz] from the zero crossings (linearly interpolated) of x.
double zero_crossing_frequency(const std::vector<double>& x, double dt) {
  std::vector<double> crossings;
  for (std::size_t i = 1; i < x.size(); ++i) {
    if ((x[i - 1] < 0.0) != (x[i] < 0.0)) {
      crossings.push_back((static_cast<double>(i - 1) + x[i - 1] / (x[i - 1] - x[i])) * dt);
    }
  }
  if (crossings.size() < 3) return 0.0;
  return 0.5 * static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
}

// Body heave and angle on the two spring-tyre pairs in series (the wheels'
// inertia neglected): the 2 x 2 eigenproblem solved by the quadratic formula.
std::array<double, 2> body_modes_by_hand(const HalfCarParams& p) {
  const double l1 = half_car_lever_arm(p, 0), l2 = half_car_lever_arm(p, 1);
  const double k1 = series(p.spring_1, p.tyre_stiffness_1), k2 = series(p.spring_2, p.tyre_stiffness_2);
  const double kzz = k1 + k2, kzp = k1 * l1 + k2 * l2, kpp = k1 * l1 * l1 + k2 * l2 * l2;
  const double m = p.mass_body, j = p.inertia_body;
  // det([kzz - m L, kzp; kzp, kpp - j L]) = 0
  const double a = m * j, b = -(kzz * j + kpp * m), c = kzz * kpp - kzp * kzp;
  const double root = std::sqrt(b * b - 4.0 * a * c);
  return {hz(std::sqrt((-b - root) / (2.0 * a))), hz(std::sqrt((-b + root) / (2.0 * a)))};
}

double wheel_hop_by_hand(double k, double kt, double mu) { return hz(std::sqrt((k + kt) / mu)); }

}  // namespace

// ---------------------------------------------------------------- equilibrium

TEST(HalfCarModel, AtRestWithoutRoadOrForceTheCarStaysInStaticEquilibrium) {
  for (HalfCarParams p : {HalfCarParams{}, HalfCarParams::roll_plane()}) {
    p.road.kind = RoadKind::kFlat;
    p.curve_radius = 0.0;
    HalfCarPlant plant(p);
    const auto run = simulate(plant, 10.0, 0.0025);
    for (const auto& s : run) {
      for (std::size_t i : {sig::kZs, sig::kPhi, sig::kZu1, sig::kZu2, sig::kZsDot, sig::kZsDdot, sig::kPhiDdot}) {
        ASSERT_EQ(s[i], 0.0) << "signal " << i;
      }
      ASSERT_EQ(s[sig::kSimContact1], 1.0);
      ASSERT_EQ(s[sig::kSimContact2], 1.0);
    }
    // The static tyre loads carry the whole weight and balance the moment.
    const double f1 = run.back()[sig::kSimTyreForce1], f2 = run.back()[sig::kSimTyreForce2];
    const double weight = (p.mass_body + p.mass_unsprung_1 + p.mass_unsprung_2) * p.gravity;
    EXPECT_NEAR(f1 + f2, weight, 1e-9 * weight);
    const double l1 = half_car_lever_arm(p, 0), l2 = half_car_lever_arm(p, 1);
    EXPECT_NEAR((f1 - p.mass_unsprung_1 * p.gravity) * l1 + (f2 - p.mass_unsprung_2 * p.gravity) * l2, 0.0, 1e-9 * weight);
  }
  // Pitch plane by hand: front 1080 g 1.156/2.68 + 85 g = 5403.8 N, rear 1080 g 1.524/2.68 + 60 g = 6613.4 N.
  HalfCarPlant plant{HalfCarParams{}};
  EXPECT_NEAR(plant.static_tyre_load(0), 5403.8, 0.1);
  EXPECT_NEAR(plant.static_tyre_load(1), 6613.4, 0.1);
}

TEST(HalfCarModel, ConstantActiveForceSettlesWhereTheSpringsBalanceIt) {
  // F1 = F2 = 500 N push body and wheels apart; the wheels' tyres see no net
  // change (internal force), so the wheels stay and the body rises by
  // F / k at each corner: z_s + l_i phi = F / k_i.
  HalfCarParams p;
  p.road.kind = RoadKind::kFlat;
  HalfCarPlant plant(p);
  const auto run = simulate(plant, 20.0, 0.0025, {500.0, 500.0});
  const auto& s = run.back();
  EXPECT_NEAR(s[sig::kZu1], 0.0, 1e-9);
  EXPECT_NEAR(s[sig::kZu2], 0.0, 1e-9);
  EXPECT_NEAR(s[sig::kTravel1], 500.0 / p.spring_1, 1e-8);
  EXPECT_NEAR(s[sig::kTravel2], 500.0 / p.spring_2, 1e-8);
}

// ---------------------------------------------------------- paper's equations

TEST(HalfCarModel, StateSpaceFormReproducesThePapersEquationsOneToFour) {
  // Roll plane (a = b = w/2), where eqs. 1-4 hold literally in corner
  // coordinates: wheel 1 = right (r), wheel 2 = left (l). Eq. 4's tyre term
  // is read as K_u (Z_ul - Z_rl) and phi = (Z_sr - Z_sl)/w.
  const HalfCarParams p = HalfCarParams::roll_plane();
  const HalfCarModel m = HalfCarModel::build(p);
  const double ms = p.mass_body, iyy = p.inertia_body, mu = p.mass_unsprung_1, w = p.track;
  const double ks = p.spring_1, cs = p.damper_1, ku = p.tyre_stiffness_1;
  Eigen::Matrix<double, 8, 1> x;
  x << 0.011, -0.023, 0.004, -0.007, 0.31, -0.52, 0.9, -1.3;
  const Eigen::Vector2d f(700.0, -300.0), r(0.02, -0.015);
  const Eigen::Matrix<double, 8, 1> dx = m.A * x + m.B * f + m.E * r;
  const Eigen::Matrix<double, 8, 1> y = m.paper_transform() * x;    // [Zsr', Zur', Zsl', Zul', Zsr, Zur, Zsl, Zul]
  const Eigen::Matrix<double, 8, 1> dy = m.paper_transform() * dx;  // their derivatives
  const double zs_dd = dx(half_car_state::kVs), phi_dd = dx(half_car_state::kOmega);
  const double dsr = y(0) - y(1), dsl = y(2) - y(3), sr = y(4) - y(5), sl = y(6) - y(7);
  EXPECT_NEAR(ms * zs_dd + cs * dsr + cs * dsl + ks * sr + ks * sl, f(0) + f(1), 1e-8);  // eq. 1
  EXPECT_NEAR(iyy * phi_dd + 0.5 * w * cs * dsr - 0.5 * w * cs * dsl + 0.5 * w * ks * sr - 0.5 * w * ks * sl,
              0.5 * w * f(0) - 0.5 * w * f(1), 1e-8);                                            // eq. 2
  EXPECT_NEAR(mu * dy(1) - cs * dsr - ks * sr + ku * (y(5) - r(0)), -f(0), 1e-8);                 // eq. 3
  EXPECT_NEAR(mu * dy(3) - cs * dsl - ks * sl + ku * (y(7) - r(1)), -f(1), 1e-8);                 // eq. 4
  // Constraints: Z_s = (Z_sr + Z_sl)/2, phi = (Z_sr - Z_sl)/w.
  EXPECT_NEAR(0.5 * (y(4) + y(6)), x(0), 1e-15);
  EXPECT_NEAR((y(4) - y(6)) / w, x(1), 1e-15);
}

TEST(HalfCarModel, SimulatorAndStateSpaceModelAgreeWhileTheTyresTouch) {
  // One RK4 step of the plant from a state with small motion equals the
  // linear model's derivative (accelerations via measure()).
  HalfCarParams p;
  p.road.kind = RoadKind::kFlat;
  HalfCarPlant plant(p);
  HalfCarState s;
  s.z_s = 0.004;
  s.phi = -0.002;
  s.z_u1 = 0.003;
  s.z_u2 = -0.001;
  s.v_s = 0.05;
  s.omega = 0.02;
  s.v_u1 = -0.1;
  s.v_u2 = 0.2;
  s.f_act1 = 150.0;
  s.f_act2 = -80.0;
  plant.set_state(s);
  Signals out;
  plant.measure(out);
  const HalfCarModel m = HalfCarModel::build(p);
  Eigen::Matrix<double, 8, 1> x;
  x << s.z_s, s.phi, s.z_u1, s.z_u2, s.v_s, s.omega, s.v_u1, s.v_u2;
  const Eigen::Matrix<double, 8, 1> dx = m.A * x + m.B * Eigen::Vector2d(s.f_act1, s.f_act2);
  EXPECT_NEAR(out[sig::kZsDdot], dx(half_car_state::kVs), 1e-10);
  EXPECT_NEAR(out[sig::kPhiDdot], dx(half_car_state::kOmega), 1e-10);
}

TEST(HalfCarModel, RoadAndTyreDampingEnterAsInTheStateSpaceModel) {
  // Mid-bump, with tyre damping: plant accelerations = A x + B f + E r + E_rate r'.
  HalfCarParams p;
  p.tyre_damping_1 = 400.0;
  p.tyre_damping_2 = 300.0;
  HalfCarPlant plant(p);
  HalfCarState s;
  s.time = p.road.bump.start_time + 0.0031;  // wheel 1 on the first hump, wheel 2 not yet
  s.z_u1 = 0.01;
  s.v_u1 = 0.4;
  s.v_s = -0.02;
  plant.set_state(s);
  Signals out;
  plant.measure(out);
  const HalfCarModel m = HalfCarModel::build(p);
  Eigen::Matrix<double, 8, 1> x;
  x << s.z_s, s.phi, s.z_u1, s.z_u2, s.v_s, s.omega, s.v_u1, s.v_u2;
  const RoadSample r1 = plant.road().at(0, s.time), r2 = plant.road().at(1, s.time);
  EXPECT_GT(r1.z, 0.01);
  EXPECT_EQ(r2.z, 0.0);
  const Eigen::Matrix<double, 8, 1> dx =
      m.A * x + m.E * Eigen::Vector2d(r1.z, r2.z) + m.E_rate * Eigen::Vector2d(r1.dz, r2.dz);
  EXPECT_NEAR(out[sig::kZsDdot], dx(half_car_state::kVs), 1e-9);
  EXPECT_NEAR(out[sig::kPhiDdot], dx(half_car_state::kOmega), 1e-9);
  EXPECT_NEAR(out[sig::kZr1], r1.z, 0.0);
}

TEST(HalfCarModel, OptionalActuatorLagAndDamperAsymmetry) {
  HalfCarParams p;
  p.road.kind = RoadKind::kFlat;
  p.actuator_time_constant = 0.02;
  HalfCarPlant lagged(p);
  const auto run = simulate(lagged, 0.02, 0.0025, {1000.0, -500.0});
  EXPECT_NEAR(run.back()[sig::kSimFAct1], 1000.0 * (1.0 - std::exp(-1.0)), 0.5);
  EXPECT_NEAR(run.back()[sig::kSimFAct2], -500.0 * (1.0 - std::exp(-1.0)), 0.5);
  // Rebound (extension) damped twice as hard as compression.
  HalfCarParams q;
  q.road.kind = RoadKind::kFlat;
  q.damper_rebound_factor = 2.0;
  for (double v : {0.1, -0.1}) {
    HalfCarPlant plant(q);
    HalfCarState s;
    s.v_s = v;  // body moving: both suspensions extend (v > 0) or compress
    plant.set_state(s);
    Signals out;
    plant.measure(out);
    const double c = v > 0.0 ? 2.0 : 1.0;
    EXPECT_NEAR(out[sig::kZsDdot], -c * (q.damper_1 + q.damper_2) * v / q.mass_body, 1e-12) << v;
  }
}

// ----------------------------------------------------------- eigenfrequencies

TEST(HalfCarModel, EigenfrequenciesMatchTheHandCalculation) {
  const HalfCarParams p;  // docs/rig-models.md 3.3, pitch plane
  const HalfCarModel m = HalfCarModel::build(p);
  const auto modes = m.modes();
  ASSERT_EQ(modes.size(), 4u);
  const auto body = body_modes_by_hand(p);
  const double hop1 = wheel_hop_by_hand(p.spring_1, p.tyre_stiffness_1, p.mass_unsprung_1);
  const double hop2 = wheel_hop_by_hand(p.spring_2, p.tyre_stiffness_2, p.mass_unsprung_2);
  // Uncoupled 1-DOF estimates, for the record: with k1 a - k2 b = 44.6 kN
  // the heave and pitch of this car couple strongly and split apart.
  const double k1 = series(p.spring_1, p.tyre_stiffness_1), k2 = series(p.spring_2, p.tyre_stiffness_2);
  const double heave_1dof = hz(std::sqrt((k1 + k2) / p.mass_body));
  const double pitch_1dof = hz(std::sqrt((k1 * p.dist_front * p.dist_front + k2 * p.dist_rear * p.dist_rear) / p.inertia_body));
  std::printf("model  (|lambda|/2pi): %.3f %.3f %.3f %.3f Hz, damping %.3f %.3f %.3f %.3f\n", modes[0].natural_hz,
              modes[1].natural_hz, modes[2].natural_hz, modes[3].natural_hz, modes[0].damping_ratio,
              modes[1].damping_ratio, modes[2].damping_ratio, modes[3].damping_ratio);
  std::printf("hand: body 2-DOF %.3f %.3f Hz, hop %.3f %.3f Hz; uncoupled heave %.3f pitch %.3f Hz\n", body[0],
              body[1], hop1, hop2, heave_1dof, pitch_1dof);
  // The hand calculation neglects the wheels' inertia in the body modes and
  // the body's motion in the hop modes: errors of order (f_body/f_hop)^2,
  // about 2 %. Damping moves |lambda| by less than 1 %.
  EXPECT_NEAR(modes[0].natural_hz, body[0], 0.02 * body[0]);
  EXPECT_NEAR(modes[1].natural_hz, body[1], 0.02 * body[1]);
  EXPECT_NEAR(modes[2].natural_hz, hop1, 0.02 * hop1);
  EXPECT_NEAR(modes[3].natural_hz, hop2, 0.02 * hop2);
  EXPECT_EQ(modes[0].dominant, HalfCarDof::kHeave);
  EXPECT_EQ(modes[1].dominant, HalfCarDof::kAngle);
  EXPECT_EQ(modes[2].dominant, HalfCarDof::kWheel1);
  EXPECT_EQ(modes[3].dominant, HalfCarDof::kWheel2);
  // The expectation: body heave near 1-1.5 Hz, wheel hop near 10 Hz.
  EXPECT_GT(modes[0].natural_hz, 1.0);
  EXPECT_LT(modes[0].natural_hz, 1.5);
  EXPECT_GT(modes[2].natural_hz, 8.5);
  EXPECT_LT(modes[3].natural_hz, 11.0);
}

TEST(HalfCarModel, UncoupledOneDofFormulasHoldWhenTheCarIsSymmetric) {
  // Roll plane: a symmetric car decouples heave and roll exactly, so the
  // 1-DOF formulas sqrt(2 k_e / m), sqrt(k_e w^2 / 2 / I) (k_e: spring and
  // tyre in series) and sqrt((k + kt)/mu) apply, up to the wheel-inertia
  // error of the series-spring reduction (~2 %).
  const HalfCarParams p = HalfCarParams::roll_plane();
  const HalfCarModel m = HalfCarModel::build(p);
  const Eigen::Vector4d f = m.undamped_frequencies_hz();
  const double ke = series(p.spring_1, p.tyre_stiffness_1);
  const double heave = hz(std::sqrt(2.0 * ke / p.mass_body));
  const double roll = hz(std::sqrt(ke * p.track * p.track / 2.0 / p.inertia_body));
  const double hop = wheel_hop_by_hand(p.spring_1, p.tyre_stiffness_1, p.mass_unsprung_1);
  std::printf("roll plane model %.3f %.3f %.3f %.3f Hz; hand heave %.3f roll %.3f hop %.3f Hz\n", f(0), f(1), f(2),
              f(3), heave, roll, hop);
  EXPECT_NEAR(f(0), heave, 0.02 * heave);
  EXPECT_NEAR(f(1), roll, 0.02 * roll);
  EXPECT_NEAR(f(2), hop, 0.02 * hop);
  EXPECT_NEAR(f(3), hop, 0.03 * hop);  // the anti-phase (roll) hop mode also loads the roll stiffness
}

TEST(HalfCarModel, FreeResponseZeroCrossingsGiveTheModeFrequencies) {
  // Undamped car started on each mode shape (eigenvectors of (K, M)): the
  // simulator's response must cross zero at the modal frequency, and that
  // frequency must match the hand calculation for the chosen parameters.
  HalfCarParams p;
  p.road.kind = RoadKind::kFlat;
  p.damper_1 = p.damper_2 = 0.0;
  p.substeps = 1;
  const HalfCarModel m = HalfCarModel::build(p);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix4d> es(m.K, m.M);
  const auto body = body_modes_by_hand(p);
  const std::array<double, 4> hand = {body[0], body[1],
                                      wheel_hop_by_hand(p.spring_1, p.tyre_stiffness_1, p.mass_unsprung_1),
                                      wheel_hop_by_hand(p.spring_2, p.tyre_stiffness_2, p.mass_unsprung_2)};
  const std::array<std::size_t, 4> watch = {sig::kZs, sig::kPhi, sig::kZu1, sig::kZu2};
  for (int mode = 0; mode < 4; ++mode) {
    Eigen::Vector4d v = es.eigenvectors().col(mode);
    v *= 1e-3 / v.cwiseAbs().maxCoeff();  // 1 mm (or mrad) amplitude: tyres stay in contact
    HalfCarPlant plant(p);
    HalfCarState s;
    s.z_s = v(0);
    s.phi = v(1);
    s.z_u1 = v(2);
    s.z_u2 = v(3);
    plant.set_state(s);
    const double f_model = std::sqrt(es.eigenvalues()(mode)) / (2.0 * kPi);
    const double dt = 1.0 / (f_model * 400.0);
    const auto run = simulate(plant, 10.0 / f_model, dt);
    std::vector<double> x;
    for (const auto& r : run) x.push_back(r[watch[static_cast<std::size_t>(mode)]]);
    const double f_sim = zero_crossing_frequency(x, dt);
    std::printf("mode %d: simulated %.4f Hz, model %.4f Hz, hand %.4f Hz\n", mode, f_sim, f_model,
                hand[static_cast<std::size_t>(mode)]);
    EXPECT_NEAR(f_sim, f_model, 1e-3 * f_model);
    EXPECT_NEAR(f_sim, hand[static_cast<std::size_t>(mode)], 0.02 * hand[static_cast<std::size_t>(mode)]);
  }
}

// ----------------------------------------------------------------------- bump

TEST(HalfCarModel, BumpFollowsEquationsNineAndTen) {
  HalfCarParams p;  // paper's bump: a0 0.05 m, lambda0 0.2 m, V 20 m/s, two humps
  HalfCarPlant plant(p);
  const RoadProfile& road = plant.road();
  const double t0 = p.road.bump.start_time, td = (p.dist_front + p.dist_rear) / p.speed;
  EXPECT_NEAR(road.delay(1), 0.134, 1e-12);  // eq. 11: (1.524 + 1.156) / 20
  // Front: a0/2 (1 - cos(2 pi V t / lambda0)) for 0 <= t <= 2 lambda0 / V = 20 ms.
  EXPECT_EQ(road.height(0, t0 - 1e-6), 0.0);
  EXPECT_NEAR(road.height(0, t0 + 0.005), 0.05, 1e-12);  // crest of the first hump
  EXPECT_NEAR(road.height(0, t0 + 0.010), 0.0, 1e-12);
  EXPECT_NEAR(road.height(0, t0 + 0.015), 0.05, 1e-12);  // second hump
  EXPECT_NEAR(road.height(0, t0 + 0.0025), 0.025, 1e-12);
  EXPECT_EQ(road.height(0, t0 + 0.0201), 0.0);
  // Rear: the same, t_d later (eq. 10).
  for (double t = 0.0; t < 1.0; t += 0.0007) EXPECT_NEAR(road.height(1, t + td), road.height(0, t), 1e-12);
  // One-wheel input: only wheel 1 sees it.
  p.road.wheels = RoadWheels::kWheel1;
  HalfCarPlant one(p);
  EXPECT_NEAR(one.road().height(0, t0 + 0.005), 0.05, 1e-12);
  EXPECT_EQ(one.road().height(1, t0 + td + 0.005), 0.0);
}

namespace {

// Lag [s] of b behind a at the peak of their cross-correlation (searched
// over 0..max_lag, refined by a parabola through the peak).
double xcorr_lag(const std::vector<double>& a, const std::vector<double>& b, double dt, double max_lag_s) {
  const auto max_lag = static_cast<std::size_t>(max_lag_s / dt);
  std::vector<double> c(max_lag + 1, 0.0);
  for (std::size_t lag = 0; lag <= max_lag; ++lag) {
    for (std::size_t i = 0; i + lag < a.size(); ++i) c[lag] += a[i] * b[i + lag];
  }
  const auto best = static_cast<std::size_t>(std::max_element(c.begin() + 1, c.end() - 1) - c.begin());
  const double d = 0.5 * (c[best - 1] - c[best + 1]) / (c[best - 1] - 2.0 * c[best] + c[best + 1]);
  return (static_cast<double>(best) + d) * dt;
}

}  // namespace

TEST(HalfCarModel, RearWheelRespondsToTheBumpDelayedByWheelbaseOverSpeed) {
  HalfCarParams p;
  const double dt = 0.00025;
  HalfCarPlant plant(p);
  const auto run = simulate(plant, 1.5, dt);
  const double td = (p.dist_front + p.dist_rear) / p.speed;
  std::vector<double> z1, z2, f1, f2;
  for (const auto& s : run) {
    z1.push_back(s[sig::kZu1]);
    z2.push_back(s[sig::kZu2]);
    f1.push_back(s[sig::kSimTyreForce1] - plant.static_tyre_load(0));
    f2.push_back(s[sig::kSimTyreForce2] - plant.static_tyre_load(1));
  }
  const double lag_wheel = xcorr_lag(z1, z2, dt, 0.3);
  const double lag_tyre = xcorr_lag(f1, f2, dt, 0.3);
  // Onset: first time each wheel moves by 10 % of its peak.
  auto onset = [&](const std::vector<double>& z) {
    double peak = 0.0;
    for (double v : z) peak = std::max(peak, std::abs(v));
    for (std::size_t i = 0; i < z.size(); ++i) {
      if (std::abs(z[i]) > 0.1 * peak) return static_cast<double>(i) * dt;
    }
    return 0.0;
  };
  const double lag_onset = onset(z2) - onset(z1);
  std::printf("t_d = %.4f s; rear behind front: tyre-force cross-correlation %.4f s, wheel-displacement "
              "cross-correlation %.4f s, wheel onset %.4f s\n",
              td, lag_tyre, lag_wheel, lag_onset);
  // The tyre force is dominated by the 20 ms road impulse itself, so its
  // correlation peak sits at t_d to within a sample or two.
  EXPECT_NEAR(lag_tyre, td, 0.001);
  EXPECT_NEAR(lag_onset, td, 0.001);
  // The wheel displacements ring at different hop frequencies (85/60 kg,
  // 80/45 kN/m: 9.2 and 10.2 Hz) and the rear feels the front bump through
  // the body first, which moves their correlation peak some ms off t_d.
  EXPECT_NEAR(lag_wheel, td, 0.010);
}

// ------------------------------------------------------------------- lift-off

TEST(HalfCarModel, TyreKeepsContactOnThePapersBumpWithoutControl) {
  HalfCarPlant plant{HalfCarParams{}};
  const auto run = simulate(plant, 3.0, 0.00025);
  double min1 = 1e9, min2 = 1e9;
  for (const auto& s : run) {
    min1 = std::min(min1, s[sig::kSimTyreForce1]);
    min2 = std::min(min2, s[sig::kSimTyreForce2]);
    ASSERT_EQ(s[sig::kSimContact1], 1.0);
    ASSERT_EQ(s[sig::kSimContact2], 1.0);
  }
  std::printf("passive, paper's bump: least tyre load front %.0f N (static %.0f), rear %.0f N (static %.0f)\n", min1,
              plant.static_tyre_load(0), min2, plant.static_tyre_load(1));
  EXPECT_GT(min1, 0.0);
  EXPECT_GT(min2, 0.0);
}

TEST(HalfCarModel, LiftOffIsFlaggedAndTheTyreNeverPulls) {
  HalfCarParams p;
  p.road.bump.amplitude = 0.20;  // four times the paper's bump: the wheel is thrown off the road
  HalfCarPlant plant(p);
  const auto run = simulate(plant, 3.0, 0.00025);
  double lifted = 0.0;
  for (const auto& s : run) {
    for (auto [f, c] : {std::pair{sig::kSimTyreForce1, sig::kSimContact1}, std::pair{sig::kSimTyreForce2, sig::kSimContact2}}) {
      ASSERT_GE(s[f], 0.0);
      if (s[c] == 0.0) {
        ASSERT_EQ(s[f], 0.0);
      }
    }
    if (s[sig::kSimContact1] == 0.0) lifted += 0.00025;
  }
  std::printf("0.2 m bump: front wheel airborne for %.1f ms\n", lifted * 1e3);
  EXPECT_GT(lifted, 0.005);
  EXPECT_EQ(run.back()[sig::kSimContact1], 1.0);  // lands again
  EXPECT_EQ(run.back()[sig::kSimContact2], 1.0);

  // Forced: a 6 kN actuator force at the front wheel-hop frequency shakes
  // wheel 1 off the road (the actuator is internal, so only the dynamics,
  // never a steady force, can unload a tyre).
  HalfCarParams q;
  q.road.kind = RoadKind::kFlat;
  HalfCarPlant shaken(q);
  const double f_hop = HalfCarModel::build(q).modes()[2].damped_hz;
  double shaken_lifted = 0.0;
  Signals s;
  for (int k = 0; k < 4000; ++k) {
    const std::array<double, 2> f = {6000.0 * std::sin(2.0 * kPi * f_hop * k * 0.0005), 0.0};
    shaken.advance(f, 0.0005);
    shaken.measure(s);
    ASSERT_GE(s[sig::kSimTyreForce1], 0.0);
    if (s[sig::kSimContact1] == 0.0) {
      ASSERT_EQ(s[sig::kSimTyreForce1], 0.0);
      shaken_lifted += 0.0005;
    }
  }
  std::printf("6 kN at %.2f Hz: front wheel airborne for %.1f ms of 2 s\n", f_hop, shaken_lifted * 1e3);
  EXPECT_GT(shaken_lifted, 0.05);
}

// ----------------------------------------------------------------- roll plane

TEST(HalfCarModel, CentrifugalMomentGivesTheHandCalculatedSteadyRoll) {
  HalfCarParams p = HalfCarParams::roll_plane();  // R 100 m at 20 m/s, h_roll 0.5 m, from 0.5 s
  HalfCarPlant plant(p);
  const auto run = simulate(plant, 10.0, 0.0025);
  // M = m V^2 / R h = 1080 * 400 / 100 * 0.5 = 2160 N m (eqs. 6-7); each
  // side's spring and tyre in series carry +-M/w, so
  // phi = 2 M / (w^2 k_e), k_e = k kt / (k + kt).
  const double moment = p.mass_body * p.speed * p.speed / p.curve_radius * p.roll_arm;
  EXPECT_NEAR(moment, 2160.0, 1e-9);
  const double ke = series(p.spring_1, p.tyre_stiffness_1);
  const double phi_hand = 2.0 * moment / (p.track * p.track * ke);
  std::printf("steady roll: simulated %.5f rad, hand %.5f rad (%.2f deg)\n", run.back()[sig::kPhi], phi_hand,
              phi_hand * 180.0 / kPi);
  EXPECT_NEAR(run.back()[sig::kPhi], phi_hand, 0.002 * phi_hand);
  EXPECT_GT(run.back()[sig::kPhi], 0.0);           // rolls outwards: wheel-1 side (curve centre side) up
  EXPECT_NEAR(run.back()[sig::kZs], 0.0, 1e-9);    // symmetric car: no heave
  EXPECT_EQ(run.front()[sig::kSimMRoll], 0.0);     // before the curve
  EXPECT_NEAR(run.back()[sig::kSimMRoll], moment, 1e-9);
  // The linear model's static gain agrees: x = -A^-1 e_roll M.
  const HalfCarModel m = HalfCarModel::build(p);
  const Eigen::Matrix<double, 8, 1> x = -m.A.fullPivLu().solve(m.e_roll * moment);
  EXPECT_NEAR(x(half_car_state::kPhi), phi_hand, 1e-9);
}

// ------------------------------------------------------------------ ISO 8608

namespace {

RoadProfile iso_road(IsoRoadClass c, uint64_t seed, WheelArrangement arrangement = WheelArrangement::kSideBySide) {
  RoadProfileSpec spec;
  spec.kind = RoadKind::kIso8608;
  spec.iso.road_class = c;
  spec.iso.seed = seed;
  return RoadProfile(spec, 20.0, arrangement, 2.68);
}

}  // namespace

TEST(HalfCarRoad, Iso8608ClassVarianceMatchesTheStandard) {
  // sigma^2 = Gd(n0) n0^2 (1/n_min - 1/n_max) over 0.011-2.83 cycle/m:
  // class A (16e-6 m^3) 1.449e-5 m^2 (3.8 mm RMS), each class 4x the last.
  const char* names = "ABCDE";
  const std::array<IsoRoadClass, 5> classes = {IsoRoadClass::kA, IsoRoadClass::kB, IsoRoadClass::kC, IsoRoadClass::kD,
                                               IsoRoadClass::kE};
  for (std::size_t c = 0; c < classes.size(); ++c) {
    const RoadProfile road = iso_road(classes[c], 7);
    const double expected = iso8608_gd_n0(classes[c]) * 0.01 * (1.0 / 0.011 - 1.0 / 2.83);
    EXPECT_NEAR(road.iso_variance(), expected, 1e-12);
    // Sample variance over 10 km (the longest wave, 91 m, repeats 110 times):
    // within 10 % of the class value.
    double sum = 0.0, sq = 0.0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
      const double z = road.track_height(0, 0.05 * i);
      sum += z;
      sq += z * z;
    }
    const double var = sq / n - (sum / n) * (sum / n);
    std::printf("class %c: RMS %.2f mm (expected %.2f mm)\n", names[c], std::sqrt(var) * 1e3, std::sqrt(expected) * 1e3);
    EXPECT_NEAR(var, expected, 0.10 * expected);
  }
}

TEST(HalfCarRoad, Iso8608PsdFollowsGdOfN0TimesNToTheMinusTwo) {
  // Averaged Hann-windowed periodogram of 200 m segments over 20 km of a
  // class C road; Gd(n) (n/n0)^2 averaged over bins near n0 = 0.1 and near
  // 1 cycle/m must be within 25 % of Gd(n0) = 256e-6 m^3.
  const RoadProfile road = iso_road(IsoRoadClass::kC, 3);
  const double dx = 0.05, seg = 200.0;
  const int n = static_cast<int>(seg / dx);
  std::vector<double> window(static_cast<std::size_t>(n));
  double wsum = 0.0;
  for (int i = 0; i < n; ++i) {
    window[static_cast<std::size_t>(i)] = 0.5 * (1.0 - std::cos(2.0 * kPi * i / n));
    wsum += window[static_cast<std::size_t>(i)] * window[static_cast<std::size_t>(i)];
  }
  auto estimate = [&](double n_lo, double n_hi) {
    double acc = 0.0;
    int count = 0;
    std::vector<double> z(static_cast<std::size_t>(n));
    for (int s = 0; s < 100; ++s) {
      for (int i = 0; i < n; ++i) z[static_cast<std::size_t>(i)] = road.track_height(0, s * seg + i * dx);
      for (int k = static_cast<int>(std::ceil(n_lo * seg)); k <= static_cast<int>(n_hi * seg); ++k) {
        std::complex<double> X = 0.0;
        for (int i = 0; i < n; ++i) {
          X += window[static_cast<std::size_t>(i)] * z[static_cast<std::size_t>(i)] * std::polar(1.0, -2.0 * kPi * k * i / n);
        }
        const double freq = k / seg;
        const double one_sided = 2.0 * std::norm(X) * dx / wsum;  // [m^2 / (cycle/m)]
        acc += one_sided * (freq / 0.1) * (freq / 0.1);
        ++count;
      }
    }
    return acc / count;
  };
  const double near_n0 = estimate(0.08, 0.125);
  const double near_1 = estimate(0.8, 1.25);
  std::printf("class C: Gd(n0) estimated %.0f e-6 (n ~ 0.1), %.0f e-6 (n ~ 1); standard 256e-6 m^3\n", near_n0 * 1e6,
              near_1 * 1e6);
  EXPECT_NEAR(near_n0, 256e-6, 0.25 * 256e-6);
  EXPECT_NEAR(near_1, 256e-6, 0.25 * 256e-6);
}

TEST(HalfCarRoad, Iso8608RoadIsReproduciblePerSeedAndDelayedAtTheRear) {
  const RoadProfile a = iso_road(IsoRoadClass::kB, 42), b = iso_road(IsoRoadClass::kB, 42), c = iso_road(IsoRoadClass::kB, 43);
  bool differs = false;
  for (double x = 0.0; x < 500.0; x += 0.37) {
    ASSERT_EQ(a.track_height(0, x), b.track_height(0, x));
    ASSERT_EQ(a.track_height(1, x), b.track_height(1, x));
    differs = differs || a.track_height(0, x) != c.track_height(0, x);
  }
  EXPECT_TRUE(differs);
  // Side by side: two different tracks. In line: the rear runs on the front's track, t_d later.
  EXPECT_NE(a.height(0, 5.0), a.height(1, 5.0));
  const RoadProfile inline_road = iso_road(IsoRoadClass::kB, 42, WheelArrangement::kInLine);
  for (double t = 0.0; t < 20.0; t += 0.013) EXPECT_NEAR(inline_road.height(1, t + 0.134), inline_road.height(0, t), 1e-12);
  // Fades in from zero: a run starting at rest sees no step.
  EXPECT_EQ(a.height(0, 0.0), 0.0);
  EXPECT_NEAR(a.height(0, 0.001), 0.0, 1e-6);
}
