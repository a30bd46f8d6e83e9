// A half car standing on two actuators, written for the tests alone (not the
// project's plant): rigid body in heave and pitch on two suspension corners
// (spring, damper with an optional rebound/compression asymmetry), two
// unsprung masses on tyre springs standing on the actuators' platens, each
// actuator a second-order closed position loop. Parameters of the half car
// of seed 001 (plant/half_car/half_car_params.hpp); the actuators' loops at
// 12 Hz, damping 0.7, like a road simulator's PI loop. Drives are held for a
// sample (zero-order hold) and the state integrated with RK4 in sub-steps.
// Responses: the body's displacement over the front and the rear axle.
#pragma once

#include <array>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Dense>

namespace rigctl::test {

class TwoPosterLinearRig {
 public:
  static constexpr int kStates = 12;
  double m_s = 1080.0, inertia = 2070.0, a = 1.524, b = 1.156;
  double m_u1 = 85.0, m_u2 = 60.0, k1 = 80000.0, k2 = 45000.0, c1 = 1500.0, c2 = 1500.0, kt = 200000.0;
  double actuator_hz = 12.0, actuator_damping = 0.7;
  double rebound_factor = 1.0;  // rebound damping / compression damping (1: a linear damper)
  double noise_m = 0.0;         // sensor noise on the responses [m rms]
  double period_s = 0.0025;

  // Records: drives[m][i] -> responses[j][i]; y[i] is the state at i T, the
  // drive d[i] held over [i T, (i + 1) T).
  std::vector<std::vector<double>> play(const std::vector<std::vector<double>>& drives, unsigned seed = 7) const {
    Eigen::Matrix<double, kStates, 1> x = Eigen::Matrix<double, kStates, 1>::Zero();
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, noise_m);
    const std::size_t n = drives.front().size();
    std::vector<std::vector<double>> y(2, std::vector<double>(n));
    constexpr int kSub = 4;
    const double h = period_s / kSub;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d out = output(x);
      y[0][i] = out(0) + (noise_m > 0.0 ? noise(rng) : 0.0);
      y[1][i] = out(1) + (noise_m > 0.0 ? noise(rng) : 0.0);
      const Eigen::Vector2d d(drives[0][i], drives[1][i]);
      for (int s = 0; s < kSub; ++s) {
        const auto k_1 = deriv(x, d);
        const auto k_2 = deriv(x + 0.5 * h * k_1, d);
        const auto k_3 = deriv(x + 0.5 * h * k_2, d);
        const auto k_4 = deriv(x + h * k_3, d);
        x += h / 6.0 * (k_1 + 2.0 * k_2 + 2.0 * k_3 + k_4);
      }
    }
    return y;
  }

  // The linear rig's sampled response (rebound_factor 1) at f: C (jw - A)^-1 B
  // times the zero-order hold's (1 - e^-jwT) / (jwT).
  Eigen::Matrix2cd frf(double f_hz) const {
    Eigen::Matrix<double, kStates, kStates> a_m;
    Eigen::Matrix<double, kStates, 2> b_m;
    const Eigen::Matrix<double, kStates, 1> zero = Eigen::Matrix<double, kStates, 1>::Zero();
    for (int c = 0; c < kStates; ++c) a_m.col(c) = linear_deriv(unit(c), Eigen::Vector2d::Zero());
    b_m.col(0) = linear_deriv(zero, Eigen::Vector2d(1, 0));
    b_m.col(1) = linear_deriv(zero, Eigen::Vector2d(0, 1));
    Eigen::Matrix<double, 2, kStates> c_m;
    for (int c = 0; c < kStates; ++c) c_m.col(c) = output(unit(c));
    const std::complex<double> jw(0.0, 2.0 * std::numbers::pi * f_hz);
    const Eigen::MatrixXcd resolvent = (jw * Eigen::MatrixXcd::Identity(kStates, kStates) - a_m.cast<std::complex<double>>()).inverse();
    const std::complex<double> hold = (1.0 - std::exp(-jw * period_s)) / (jw * period_s);
    return hold * c_m.cast<std::complex<double>>() * resolvent * b_m.cast<std::complex<double>>();
  }

 private:
  // State: z_s, phi, z_u1, z_u2, x_a1, x_a2, then their rates.
  static Eigen::Matrix<double, kStates, 1> unit(int c) {
    Eigen::Matrix<double, kStates, 1> e = Eigen::Matrix<double, kStates, 1>::Zero();
    e(c) = 1.0;
    return e;
  }
  Eigen::Vector2d output(const Eigen::Matrix<double, kStates, 1>& x) const {
    return {x(0) + a * x(1), x(0) - b * x(1)};
  }
  double damper(double c, double extension_rate) const {
    return extension_rate > 0.0 ? c * rebound_factor * extension_rate : c * extension_rate;
  }
  Eigen::Matrix<double, kStates, 1> deriv(const Eigen::Matrix<double, kStates, 1>& x, const Eigen::Vector2d& d) const {
    return derivative(x, d, true);
  }
  Eigen::Matrix<double, kStates, 1> linear_deriv(const Eigen::Matrix<double, kStates, 1>& x, const Eigen::Vector2d& d) const {
    return derivative(x, d, false);
  }
  Eigen::Matrix<double, kStates, 1> derivative(const Eigen::Matrix<double, kStates, 1>& x, const Eigen::Vector2d& d,
                                               bool asymmetric) const {
    const double zb1 = x(0) + a * x(1), zb2 = x(0) - b * x(1);
    const double vb1 = x(6) + a * x(7), vb2 = x(6) - b * x(7);
    const double ext1 = vb1 - x(8), ext2 = vb2 - x(9);  // extension rates of the corners
    const double damping1 = asymmetric ? damper(c1, ext1) : c1 * ext1;
    const double damping2 = asymmetric ? damper(c2, ext2) : c2 * ext2;
    const double f1 = k1 * (x(2) - zb1) - damping1;  // on the body, up
    const double f2 = k2 * (x(3) - zb2) - damping2;
    const double w = 2.0 * std::numbers::pi * actuator_hz;
    Eigen::Matrix<double, kStates, 1> dx;
    dx.head<6>() = x.tail<6>();
    dx(6) = (f1 + f2) / m_s;
    dx(7) = (a * f1 - b * f2) / inertia;
    dx(8) = (-f1 + kt * (x(4) - x(2))) / m_u1;
    dx(9) = (-f2 + kt * (x(5) - x(3))) / m_u2;
    dx(10) = w * w * (d(0) - x(4)) - 2.0 * actuator_damping * w * x(10);
    dx(11) = w * w * (d(1) - x(5)) - 2.0 * actuator_damping * w * x(11);
    return dx;
  }
};

}  // namespace rigctl::test
