#include "tools/diagnosis/sensor_filter.hpp"

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>

namespace rigctl::diag {

namespace {

// Denominators P(s) = c0 + c1 s + ... + cn s^n of the forms (H = 1 / P), each
// normalised to c0 = c1 = 1: unit gain and unit group delay at low
// frequency, so P(tau s) has group delay tau. Bessel: the reverse Bessel
// polynomials over their constant term (n = 2: s^2 + 3 s + 3); Butterworth:
// the polynomials with corner 1 rad/s, s scaled by 1 / c1 (c1 = 1 / sin(pi / 2n)).
struct Denominator {
  int order;
  std::array<double, 5> c;
};
Denominator denominator(SensorForm form) {
  switch (form) {
    case SensorForm::kFirstOrderLag: return {1, {1.0, 1.0}};
    case SensorForm::kBessel2: return {2, {1.0, 1.0, 1.0 / 3.0}};
    case SensorForm::kBessel3: return {3, {1.0, 1.0, 6.0 / 15.0, 1.0 / 15.0}};
    case SensorForm::kBessel4: return {4, {1.0, 1.0, 45.0 / 105.0, 10.0 / 105.0, 1.0 / 105.0}};
    case SensorForm::kButterworth2: return {2, {1.0, 1.0, 0.5}};
    case SensorForm::kButterworth3: return {3, {1.0, 1.0, 0.5, 0.125}};
    case SensorForm::kButterworth4: {
      const double a1 = 1.0 / std::sin(M_PI / 8.0);  // 2.6131
      return {4, {1.0, 1.0, (2.0 + std::sqrt(2.0)) / (a1 * a1), a1 / (a1 * a1 * a1), 1.0 / (a1 * a1 * a1 * a1)}};
    }
    case SensorForm::kPureDelay: break;
  }
  return {0, {}};
}

// Below this share of a sample a sensor's group delay changes no sample by
// more than 1e-4 of its step: the sensor is taken as exact (the filter's
// discretisation would be needlessly stiff).
constexpr double kNegligibleShare = 1e-4;

}  // namespace

std::string to_string(SensorForm form) {
  switch (form) {
    case SensorForm::kPureDelay: return "pure_delay";
    case SensorForm::kFirstOrderLag: return "first_order_lag";
    case SensorForm::kBessel2: return "bessel_2";
    case SensorForm::kBessel3: return "bessel_3";
    case SensorForm::kBessel4: return "bessel_4";
    case SensorForm::kButterworth2: return "butterworth_2";
    case SensorForm::kButterworth3: return "butterworth_3";
    case SensorForm::kButterworth4: return "butterworth_4";
  }
  return "?";
}

std::vector<std::string> sensor_form_names() {
  std::vector<std::string> names;
  for (auto f : kSensorForms) names.push_back(to_string(f));
  return names;
}

SensorForm sensor_form_at(double index) {
  const long i = std::lround(index);
  return kSensorForms[static_cast<std::size_t>(std::clamp<long>(i, 0, static_cast<long>(kSensorForms.size()) - 1))];
}

SensorFilter::SensorFilter(SensorForm form, double tau, double dt) : form_(form), tau_(tau), dt_(dt) {
  active_ = tau > kNegligibleShare * dt;
  if (!active_ || form == SensorForm::kPureDelay) return;
  const Denominator d = denominator(form);
  order_ = d.order;
  const int n = order_;
  // States q_k = tau^k z^(k): the companion matrix is A / tau with O(1)
  // entries whatever tau, so exp(A h) stays well conditioned.
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(n + 2, n + 2);
  for (int k = 0; k + 1 < n; ++k) F(k, k + 1) = 1.0 / tau;
  for (int k = 0; k < n; ++k) F(n - 1, k) = -d.c[static_cast<std::size_t>(k)] / (d.c[static_cast<std::size_t>(n)] * tau);
  F(n - 1, n) = 1.0 / (d.c[static_cast<std::size_t>(n)] * tau);  // the input u
  F(n, n + 1) = 1.0;                                             // u' = r, r' = 0: u linear over the step
  const Eigen::MatrixXd M = (F * dt).exp();
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) phi_[static_cast<std::size_t>(r * 4 + c)] = M(r, c);
    g0_[static_cast<std::size_t>(r)] = M(r, n);
    g1_[static_cast<std::size_t>(r)] = M(r, n + 1) / dt;  // per unit change of u over the step
  }
}

std::complex<double> SensorFilter::response(double omega) const {
  if (!active_) return {1.0, 0.0};
  if (form_ == SensorForm::kPureDelay) return std::polar(1.0, -omega * tau_);
  const Denominator d = denominator(form_);
  const std::complex<double> s(0.0, omega * tau_);
  std::complex<double> p(0.0, 0.0), sk(1.0, 0.0);
  for (int k = 0; k <= d.order; ++k, sk *= s) p += d.c[static_cast<std::size_t>(k)] * sk;
  return 1.0 / p;
}

void SensorFilter::reset(double x0) {
  u_prev_ = x0;
  x_.fill(0.0);
  x_[0] = x0;
  history_.clear();
  history_.push_back(x0);
}

double SensorFilter::step(double x) {
  if (!active_) return x;
  if (form_ == SensorForm::kPureDelay) {
    history_.push_back(x);
    // history_[0] is the value at rest before the start; the current sample is last.
    const double s = static_cast<double>(history_.size() - 1) - tau_ / dt_;
    if (s <= 0.0) return history_.front();
    const auto i = static_cast<std::size_t>(s);
    const double a = s - static_cast<double>(i);
    return i + 1 < history_.size() ? history_[i] + a * (history_[i + 1] - history_[i]) : history_.back();
  }
  const int n = order_;
  std::array<double, 4> next{};
  const double du = x - u_prev_;
  for (int r = 0; r < n; ++r) {
    double v = g0_[static_cast<std::size_t>(r)] * u_prev_ + g1_[static_cast<std::size_t>(r)] * du;
    for (int c = 0; c < n; ++c) v += phi_[static_cast<std::size_t>(r * 4 + c)] * x_[static_cast<std::size_t>(c)];
    next[static_cast<std::size_t>(r)] = v;
  }
  x_ = next;
  u_prev_ = x;
  return x_[0];
}

void SensorFilter::apply(std::vector<double>& y) {
  if (!active_ || y.empty()) return;
  reset(y.front());
  for (auto& v : y) v = step(v);
}

}  // namespace rigctl::diag
