// Sensors in the forms rigs have (tools/diagnosis/sensor_filter.*, issue 34):
// every form delays a slow signal by its group delay tau, the filters have
// the textbook responses of their families, and the diagnosis names which
// channel is late and in which form. The filters are checked against
// properties any textbook states (a Butterworth is 3 dB down at its corner,
// a ramp through a filter lags by its DC group delay), not against their
// own formulas.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/diagnosis/sensor_filter.hpp"
#include "tools/diagnosis/util.hpp"

namespace rigctl::diag {
namespace {

constexpr double kPi = std::numbers::pi;

// A ramp through any form, once the start has died out, lags by tau: the
// low-frequency group delay every form is parameterised by.
TEST(DiagnosisSensorForms, EveryFormDelaysARampByItsGroupDelay) {
  const double dt = 0.0025, tau = 0.012;
  for (auto form : kSensorForms) {
    SensorFilter f(form, tau, dt);
    f.reset(0.0);
    double out = 0.0;
    const int n = 2000;  // 5 s: the slowest form (the lag) settles in a few tau
    for (int k = 0; k <= n; ++k) out = f.step(k * dt);
    EXPECT_NEAR(n * dt - out, tau, 1e-6) << to_string(form);
  }
}

// A Butterworth filter of order n is 3 dB down at its corner, which lies at
// omega_c = 1 / (sin(pi / 2n) tau) for DC group delay tau (its denominator's
// first coefficient is 1 / sin(pi / 2n) at corner 1 rad/s); a Bessel
// filter's gain falls monotonically and more gently.
TEST(DiagnosisSensorForms, ButterworthIsThreeDecibelsDownAtItsCorner) {
  const double tau = 0.01;
  const SensorForm forms[] = {SensorForm::kButterworth2, SensorForm::kButterworth3, SensorForm::kButterworth4};
  for (int n = 2; n <= 4; ++n) {
    const double wc = 1.0 / (std::sin(kPi / (2.0 * n)) * tau);
    const SensorFilter f(forms[n - 2], tau, 0.0025);
    EXPECT_NEAR(std::abs(f.response(wc)), 1.0 / std::sqrt(2.0), 1e-9) << n;
  }
  const SensorFilter lag(SensorForm::kFirstOrderLag, tau, 0.0025);
  EXPECT_NEAR(std::abs(lag.response(1.0 / tau)), 1.0 / std::sqrt(2.0), 1e-9);
  const SensorFilter delay(SensorForm::kPureDelay, tau, 0.0025);
  EXPECT_NEAR(std::abs(delay.response(300.0)), 1.0, 1e-12);
  EXPECT_NEAR(std::arg(delay.response(100.0)), -1.0, 1e-12);  // 100 rad/s x 10 ms
}

// Sample by sample, a sine comes out of each filter with the gain and phase
// of its frequency response: the discretisation is the continuous filter's.
TEST(DiagnosisSensorForms, SampledFilterFollowsItsFrequencyResponse) {
  const double dt = 0.0025, tau = 0.02, w = 2.0 * kPi * 6.0;
  for (auto form : kSensorForms) {
    if (form == SensorForm::kPureDelay) continue;  // interpolated, not a filter
    SensorFilter f(form, tau, dt);
    f.reset(0.0);
    const auto h = f.response(w);
    double worst = 0.0;
    for (int k = 0; k < 4000; ++k) {
      const double t = k * dt;
      const double out = f.step(std::sin(w * t));
      if (t > 2.0) worst = std::max(worst, std::abs(out - std::abs(h) * std::sin(w * t + std::arg(h))));
    }
    EXPECT_LT(worst, 2e-3) << to_string(form);
  }
}

// ------------------------------------------------------------ in a diagnosis

constexpr double kDt = 0.0025;
constexpr std::size_t kN = 8000;  // 20 s
constexpr double kNoise = 0.002;

// Broadband input: lines from 0.3 to 12 Hz, so the forms differ where the
// signal has power (a Bessel filter rolls off later than a Butterworth).
std::vector<double> broadband() {
  std::vector<double> u(kN);
  const double lines[] = {0.3, 0.9, 2.1, 3.7, 5.3, 7.9, 12.1};
  for (std::size_t i = 0; i < kN; ++i) {
    const double t = static_cast<double>(i) * kDt;
    for (std::size_t j = 0; j < std::size(lines); ++j) u[i] += std::sin(2.0 * kPi * lines[j] * t + 0.7 * j) / 3.0;
  }
  return u;
}

// Two transducers of one known input: "a" reads it through gain g_a, "b"
// through g_b. The world's "b" sits behind a conditioning filter of `form`
// and group delay `tau_b`; "a" is exact. The candidate's forms are the
// sensor forms, its parameters one group delay per channel.
class TwoSensors : public RigModel {
 public:
  TwoSensors(SensorForm form, double tau_b) : u_(broadband()) {
    for (std::size_t i = 0; i < kN; ++i) t_.push_back(static_cast<double>(i) * kDt);
    std::vector<double> a(kN), b(kN);
    for (std::size_t i = 0; i < kN; ++i) a[i] = 1.02 * u_[i], b[i] = 0.97 * u_[i];
    SensorFilter(form, tau_b, kDt).apply(b);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, kNoise);
    for (std::size_t i = 0; i < kN; ++i) a[i] += noise(rng), b[i] += noise(rng);
    outputs_ = {{"a", a}, {"b", b}};
  }
  RunFileRig rig() const override { return RunFileRig::kDamper; }
  const std::vector<Output>& outputs() const override { return outputs_; }
  const std::vector<double>& time() const override { return t_; }
  std::vector<ParamSpec> baseline() const override { return {Prior("g_a", "1", 1.0, 0.05), Prior("g_b", "1", 1.0, 0.05)}; }
  std::vector<EffectSpec> effects() const override {
    return {{"sensor_delay",
             {OnChannel(P("tau_a", "s", 0.002, 0.0, 0.1, 0.005, 0.0, true, {0.02}), "a"),
              OnChannel(P("tau_b", "s", 0.002, 0.0, 0.1, 0.005, 0.0, true, {0.02}), "b"), FormIndex()},
             "each transducer through a sensor of its own group delay",
             sensor_form_names()}};
  }
  void simulate(const std::vector<double>& th, std::vector<std::vector<double>>& y) const override {
    y.assign(2, std::vector<double>(kN));
    for (std::size_t i = 0; i < kN; ++i) y[0][i] = th[0] * u_[i], y[1][i] = th[1] * u_[i];
    const SensorForm form = sensor_form_at(th[4]);
    SensorFilter(form, th[2], kDt).apply(y[0]);
    SensorFilter(form, th[3], kDt).apply(y[1]);
  }
  std::string replay() const override { return "two transducers of a known input"; }
  Indicator indicator(const std::string&) const override { return {}; }

 private:
  std::vector<double> u_, t_;
  std::vector<Output> outputs_;
};

TEST(DiagnosisSensorForms, TheDiagnosisNamesTheLateChannelAndTheFilterItIsBehind) {
  for (auto form : {SensorForm::kBessel2, SensorForm::kButterworth4, SensorForm::kPureDelay}) {
    const TwoSensors model(form, 0.015);
    const Diagnosis d = diagnose(model, {});
    ASSERT_EQ(d.cause, "sensor_delay") << to_string(form);
    const auto& c = d.causes.front();
    std::string costs;
    for (const auto& [f, cost] : c.form_costs) costs += " " + f + " " + std::to_string(cost);
    EXPECT_EQ(c.form, to_string(form)) << costs;
    EXPECT_EQ(c.channels, std::vector<std::string>{"b"}) << to_string(form);
    for (const auto& p : c.parameters) {
      if (p.name == "tau_b") {
        EXPECT_NEAR(p.value, 0.015, 0.0015) << to_string(form);
      }
    }
    EXPECT_EQ(c.form_costs.size(), kSensorForms.size());
  }
}

}  // namespace
}  // namespace rigctl::diag
