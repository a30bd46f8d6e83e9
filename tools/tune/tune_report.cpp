#include "tools/tune/tune_report.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "tools/common/json_text.hpp"
#include "tools/tune/plant_grid.hpp"

namespace rigctl {

namespace {

// A fit further off than this (rms over the coherent points) does not
// predict a step: the plant is too nonlinear for one transfer function.
constexpr double kTrustedFitDb = 3.0;

std::string numbers(const std::vector<double>& v, std::size_t every = 1) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); i += every) s += (i ? ", " : "") + json_number(v[i]);
  return s + "]";
}

std::string margins_json(const Margins& m) {
  return "{\"crossover_hz\": " + json_number(m.crossover_hz) + ", \"phase_margin_deg\": " + json_number(m.phase_margin_deg) +
         ", \"gain_margin_db\": " + json_number(m.gain_margin_db) + ", \"phase_crossover_hz\": " +
         json_number(m.phase_crossover_hz) + ", \"gain_margin_beyond_band\": " + (m.gain_margin_beyond_band ? "true" : "false") +
         ", \"peak_sensitivity\": " + json_number(m.peak_sensitivity) + "}";
}

// The tuned loop on the FRF's coherent frequencies (where the margins come from).
std::string loop_json(const FrfData& frf, const LoopGains& g) {
  const PlantResponse p = PlantResponse::from_frf(frf);
  std::vector<double> f, re, im;
  const auto l = loop_transfer(g, p);
  for (std::size_t i = 0; i < l.size(); ++i) {
    f.push_back(p.frequency_hz[i]);
    re.push_back(l[i].real());
    im.push_back(l[i].imag());
  }
  return "{\"frequency_hz\": " + numbers(f) + ", \"re\": " + numbers(re) + ", \"im\": " + numbers(im) + "}";
}

}  // namespace

void print_margins(const char* what, const Margins& m, std::ostream& out) {
  if (!std::isfinite(m.crossover_hz)) {
    out << "  " << what << ": no crossover in the measured band, sensitivity peak " << m.peak_sensitivity << "\n";
    return;
  }
  out << "  " << what << ": crossover " << m.crossover_hz << " Hz, phase margin " << m.phase_margin_deg << " deg, gain margin "
      << (m.gain_margin_beyond_band ? "at least " : "") << m.gain_margin_db << " dB"
      << (m.gain_margin_beyond_band ? " (no phase crossover in the band)" : " at " + std::to_string(m.phase_crossover_hz) + " Hz")
      << ", sensitivity peak " << m.peak_sensitivity << "\n";
}

void print_tune(const TuneReportInput& in, std::ostream& out) {
  const TuneResult& r = *in.result;
  out << std::setprecision(4) << "rigctl tune: " << (in.options->method == TuneMethod::kRelay ? "relay (Ziegler-Nichols)" : "FRF loop shaping")
      << " for " << to_string(r.gains.kind) << ", target phase margin " << in.options->target.phase_margin_deg << " deg";
  if (in.options->target.crossover_hz) out << " at " << *in.options->target.crossover_hz << " Hz";
  out << "\n  gains:";
  for (const auto& [k, v] : r.gains.config_values()) out << " " << k << " " << v;
  out << "\n";
  if (r.feedforward) {
    const FeedforwardDesign& f = *r.feedforward;
    if (f.kff > 0.0) {
      out << "  velocity feedforward " << f.kff << " s per unit of feedback: 1 / the plant's velocity gain " << f.velocity_gain
          << " per second per unit command (|G| w, median over " << f.band_low_hz << "-" << f.band_high_hz
          << " Hz); outside the loop, so the margins are the PI's\n";
    } else {
      out << "  no velocity feedforward: " << f.reason_for_none << "\n";
    }
  }
  if (r.margins) print_margins("predicted (tuned gains on the measured plant)", *r.margins, out);
  if (r.step) {
    const auto& m = r.step->metrics;
    if (in.model && in.model->rms_error_db > kTrustedFitDb) {
      out << "  the fitted plant misses the measurement by " << in.model->rms_error_db
          << " dB rms (a nonlinear plant): the predicted step below is rough\n";
    }
    out << "  predicted standard step (" << r.step->test.step << " at " << r.step->test.step_time_s << " s): overshoot "
        << 100.0 * m.overshoot << " %, settling (2 %) " << m.settling_s << " s, IAE " << m.iae << "\n";
  }
  if (!r.note.empty()) out << "  note: " << r.note << "\n";
}

void write_tune_json(const TuneReportInput& in, const std::string& path) {
  const TuneResult& r = *in.result;
  std::ostringstream o;
  o << "{\n  \"format\": \"rigctl-tune\",\n  \"version\": 1,\n  \"rig\": " << json_string(in.rig)
    << ",\n  \"controller\": " << json_string(std::string(to_string(r.gains.kind)))
    << ",\n  \"method\": " << json_string(in.options->method == TuneMethod::kRelay ? "relay" : "frf")
    << ",\n  \"target\": {\"phase_margin_deg\": " << json_number(in.options->target.phase_margin_deg)
    << ", \"crossover_hz\": " << json_number(in.options->target.crossover_hz.value_or(NAN))
    << ", \"min_gain_margin_db\": " << json_number(in.options->target.min_gain_margin_db)
    << ", \"max_sensitivity\": " << json_number(in.options->target.max_sensitivity) << "},\n  \"gains\": {";
  bool first = true;
  for (const auto& [k, v] : r.gains.config_values()) {
    o << (first ? "" : ", ") << json_string(k) << ": " << json_number(v);
    first = false;
  }
  o << "}";
  if (r.feedforward) {
    o << ",\n  \"feedforward\": {\"velocity_feedforward\": " << json_number(r.feedforward->kff) << ", \"velocity_gain\": "
      << json_number(r.feedforward->velocity_gain) << ", \"band_hz\": [" << json_number(r.feedforward->band_low_hz) << ", "
      << json_number(r.feedforward->band_high_hz) << "], \"reason_for_none\": " << json_string(r.feedforward->reason_for_none) << "}";
  }
  if (r.present_margins) o << ",\n  \"measured_margins\": " << margins_json(*r.present_margins);
  if (r.margins) o << ",\n  \"predicted_margins\": " << margins_json(*r.margins);
  if (r.step) {
    const auto& m = r.step->metrics;
    o << ",\n  \"predicted_step\": {\"step\": " << json_number(r.step->test.step) << ", \"step_time_s\": "
      << json_number(r.step->test.step_time_s) << ", \"overshoot\": " << json_number(m.overshoot)
      << ", \"settling_s\": " << json_number(m.settling_s) << ", \"iae\": " << json_number(m.iae)
      << ", \"t\": " << numbers(r.step->t, 4) << ", \"demand\": " << numbers(r.step->demand, 4)
      << ", \"response\": " << numbers(r.step->response, 4) << "}";
  }
  if (in.model) {
    o << ",\n  \"plant_model\": {\"form\": \"position N_y(x) / (x^i D(x)), pressure N_p(x) / D(x), x = s / w0\", \"integrating\": " << (in.model->integrating ? "true" : "false") << ", \"w0\": "
      << json_number(in.model->w0) << ", \"d\": " << numbers(in.model->d) << ", \"n_position\": " << numbers(in.model->n_position)
      << ", \"n_pressure\": " << numbers(in.model->n_pressure) << ", \"rms_error_db\": " << json_number(in.model->rms_error_db) << "}";
  }
  if (in.relay) {
    const RelayResult& x = *in.relay;
    o << ",\n  \"relay\": {\"ultimate_gain\": " << json_number(x.ultimate_gain) << ", \"ultimate_period_s\": "
      << json_number(x.ultimate_period_s) << ", \"oscillation_amplitude\": " << json_number(x.oscillation_amplitude)
      << ", \"relay_amplitude\": " << json_number(x.relay_amplitude) << ", \"hysteresis\": " << json_number(x.hysteresis)
      << ", \"hold_command\": " << json_number(x.hold_command) << ", \"cycles\": " << x.cycles
      << ", \"log\": " << json_string(x.log_path) << "}";
  }
  if (in.frf) o << ",\n  \"loop\": " << loop_json(*in.frf, r.gains);
  o << "\n}\n";
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << o.str();
  if (!f.flush()) throw std::runtime_error("failed writing " + path);
}

}  // namespace rigctl
