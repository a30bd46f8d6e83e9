#include "tools/iterate/drive_frf.hpp"

#include <algorithm>
#include <stdexcept>

#include "tools/identify/plant_linearisation.hpp"
#include "tools/tune/loop_response.hpp"

namespace rigctl {

namespace {

template <typename T>
T interpolate(const std::vector<double>& f, const std::vector<T>& v, double x) {
  if (f.empty()) throw std::logic_error("drive FRF without lines");
  if (x <= f.front()) return v.front();
  if (x >= f.back()) return v.back();
  const auto hi = static_cast<std::size_t>(std::upper_bound(f.begin(), f.end(), x) - f.begin());
  const double w = (x - f[hi - 1]) / (f[hi] - f[hi - 1]);
  return v[hi - 1] * (1.0 - w) + v[hi] * w;
}

}  // namespace

std::complex<double> DriveFrf::at(double f_hz) const { return interpolate(frequency_hz, value, f_hz); }

double DriveFrf::coherence_at(double f_hz) const { return interpolate(frequency_hz, coherence, f_hz); }

DriveFrf drive_frf_from_file(const FrfData& frf, const std::string& channel, const std::string& name) {
  const FrfCurve* curve = nullptr;
  std::string known;
  for (const auto& c : frf.closed_loop) {
    if (c.response == channel) curve = &c;
    known += (known.empty() ? "" : ", ") + c.response;
  }
  if (curve == nullptr) {
    throw std::invalid_argument(name + ": no closed-loop response of '" + channel + "' (the file has " + known +
                                "; measure it with rigctl identify --response " + channel + ")");
  }
  DriveFrf d;
  d.source = "frf " + name;
  d.frequency_hz = frf.frequency_hz;
  d.value = curve->value;
  d.coherence = curve->coherence;
  if (const auto it = frf.distortion.find(channel); it != frf.distortion.end()) {
    for (std::size_t i = 0; i < d.coherence.size(); ++i) d.coherence[i] = std::min(d.coherence[i], 1.0 - it->second[i]);
  }
  return d;
}

DriveFrf drive_frf_from_model(const RigConfig& config, const std::string& channel, double operating_point,
                              const std::vector<double>& frequency_hz, const std::string& source) {
  if (config.rig != RigKind::kQuarterCar || config.controller.type != ControllerKind::kPi) {
    throw std::invalid_argument("a model FRF needs the quarter car under its PI controller (this config: " +
                                std::string(to_string(config.rig)) + ", " + std::string(to_string(config.controller.type)) +
                                "); measure one with rigctl identify and give it with --frf");
  }
  const std::string& feedback = config.controller.feedback;
  std::vector<std::string> outputs{feedback};
  if (channel != feedback) outputs.push_back(channel);
  const auto plant = sampled_frf(linearise_quarter_car(config.quarter_car, operating_point, outputs),
                                 config.loop.period_s, frequency_hz);
  const LoopGains gains = LoopGains::from_config(config);
  DriveFrf d;
  d.source = source;
  d.frequency_hz = frequency_hz;
  d.coherence.assign(frequency_hz.size(), 1.0);
  for (std::size_t i = 0; i < frequency_hz.size(); ++i) {
    const std::complex<double> position = plant[0].value[i];
    const std::complex<double> loop = loop_transfer_at(gains, frequency_hz[i], position, 0.0);
    const std::complex<double> closed = loop / (1.0 + loop);
    // The channel moves with the controlled position as the plant couples them.
    d.value.push_back(outputs.size() == 1 ? closed : closed * plant[1].value[i] / position);
  }
  return d;
}

LoopPaths loop_paths_from_model(const RigConfig& config, double operating_point, const std::vector<double>& frequency_hz,
                                const std::string& source) {
  const std::string& feedback = config.controller.feedback;
  LoopPaths p;
  p.feedback = drive_frf_from_model(config, feedback, operating_point, frequency_hz, source);
  const auto plant = sampled_frf(linearise_quarter_car(config.quarter_car, operating_point, {feedback}),
                                 config.loop.period_s, frequency_hz);
  p.command = p.feedback;
  for (std::size_t i = 0; i < frequency_hz.size(); ++i) p.command.value[i] = p.feedback.value[i] / plant[0].value[i];
  return p;
}

LoopPaths loop_paths_from_file(const FrfData& frf, const std::string& feedback, const std::string& name) {
  LoopPaths p;
  p.feedback = drive_frf_from_file(frf, feedback, name);
  const FrfCurve* plant = nullptr;
  for (const auto& c : frf.plant) {
    if (c.response == feedback) plant = &c;
  }
  if (plant == nullptr) throw std::invalid_argument(name + ": no plant curve of '" + feedback + "' (command -> " + feedback + ")");
  p.command = p.feedback;
  for (std::size_t i = 0; i < p.command.value.size(); ++i) p.command.value[i] = p.feedback.value[i] / plant->value[i];
  return p;
}

std::vector<double> model_frequencies(double step_hz, double high_hz) {
  std::vector<double> f;
  for (double x = step_hz; x <= high_hz + 1e-9; x += step_hz) f.push_back(x);
  return f;
}

}  // namespace rigctl
