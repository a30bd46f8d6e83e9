// What a sensor does to the signal it measures, in the forms rigs have
// (docs/diagnosis.md 2): a pure transport delay, a first-order lag, or a
// conditioning filter of order 2-4 (Bessel, Butterworth). Every form is
// parameterised by its group delay at low frequency, tau [s]: that is what a
// residual shows first (e = -tau dy/dt), so the forms share one parameter
// and differ only where the signal has power at the filter's corner.
//
// Used in two ways by the diagnosis sub-models: on a whole simulated series
// (a channel recorded through the sensor) and sample by sample inside a
// closed-loop replay (the controller's feedback read through the sensor).
// Internal to the diagnosis.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <string>
#include <vector>

namespace rigctl::diag {

enum class SensorForm {
  kPureDelay,
  kFirstOrderLag,
  kBessel2,
  kBessel3,
  kBessel4,
  kButterworth2,
  kButterworth3,
  kButterworth4,
};
inline constexpr std::array<SensorForm, 8> kSensorForms = {
    SensorForm::kPureDelay,    SensorForm::kFirstOrderLag, SensorForm::kBessel2,      SensorForm::kBessel3,
    SensorForm::kBessel4,      SensorForm::kButterworth2,  SensorForm::kButterworth3, SensorForm::kButterworth4};

std::string to_string(SensorForm form);
// The names of kSensorForms, in that order (EffectSpec::forms).
std::vector<std::string> sensor_form_names();
// kSensorForms[index], clamped to the list (a form index carried in a parameter vector).
SensorForm sensor_form_at(double index);

class SensorFilter {
 public:
  // A sensor of this form and low-frequency group delay tau [s], sampled every dt [s].
  SensorFilter(SensorForm form, double tau, double dt);

  // At rest at x0 (every past input x0).
  void reset(double x0);
  // The sensor's output at the next sample, whose true value is x. The input
  // is taken as linear between samples (first-order hold), exact for the
  // filters' linear dynamics.
  double step(double x);
  // The whole series through the sensor, at rest at its first value.
  void apply(std::vector<double>& y);
  // The sensor's frequency response at omega [rad/s] (a sine's gain and
  // phase through it in steady state).
  std::complex<double> response(double omega) const;
  // Whether the sensor changes the signal at all (tau > 0).
  bool active() const { return active_; }

 private:
  SensorForm form_;
  double tau_, dt_;
  bool active_ = false;
  // Pure delay: the past inputs, interpolated linearly at tau / dt samples back.
  std::vector<double> history_;
  std::size_t head_ = 0, count_ = 0;
  // Filters: state x (z and its derivatives, controllable canonical form of
  // 1 / P(s)), discretised exactly for a piecewise-linear input:
  // x+ = Phi x + G0 u_k + G1 (u_k+1 - u_k).
  int order_ = 0;
  std::array<double, 16> phi_{};
  std::array<double, 4> g0_{}, g1_{}, x_{};
  double u_prev_ = 0.0;
};

}  // namespace rigctl::diag
