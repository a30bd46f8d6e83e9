#include "tools/common/json_text.hpp"
#include "tools/suspension/compare_command.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "drivers/sim/sim_driver.hpp"
#include "plant/half_car/half_car_params.hpp"
#include "rt/loop_clock.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace fs = std::filesystem;

namespace {

int index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::runtime_error("half car plant has no signal '" + name + "'");
  return static_cast<int>(it - names.begin());
}

// Records the plant's true signals and the loop's setpoint and commands on
// every tick (the simulated driver advances the plant in read(), so the
// plant stands at the sample's instant when the record arrives).
class RecordingSink final : public TelemetrySink {
 public:
  RecordingSink(const SimulatedPlant& plant, SuspensionRecording& rec, std::size_t ticks, bool keep_rows)
      : plant_(plant), rec_(rec), keep_rows_(keep_rows), buffer_(plant.signals().size()) {
    const auto& names = rec.signal_names;
    z_r_ = {index_of(names, "z_r1"), index_of(names, "z_r2")};
    z_u_ = {index_of(names, "z_u1"), index_of(names, "z_u2")};
    travel_ = {index_of(names, "susp_travel_1"), index_of(names, "susp_travel_2")};
    contact_ = {index_of(names, "sim_contact_1"), index_of(names, "sim_contact_2")};
    tyre_ = {index_of(names, "sim_tyre_force_1"), index_of(names, "sim_tyre_force_2")};
    applied_ = {index_of(names, "sim_f_act_1"), index_of(names, "sim_f_act_2")};
    z_s_ = index_of(names, "z_s");
    z_s_ddot_ = index_of(names, "z_s_ddot");
    phi_ = index_of(names, "phi");
    phi_ddot_ = index_of(names, "phi_ddot");
    auto& run = rec_.run;
    for (auto* v : {&run.z_s, &run.z_s_ddot, &run.phi, &run.phi_ddot}) v->reserve(ticks);
    for (std::size_t i = 0; i < 2; ++i) {
      for (auto* v : {&run.travel[i], &run.tyre_deflection[i], &run.force[i], &run.contact[i]}) v->reserve(ticks);
    }
    rec_.least_tyre_load = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    if (keep_rows_) {
      rec_.t.reserve(ticks);
      rec_.setpoint.reserve(ticks);
      rec_.command.reserve(ticks);
      rec_.truth.reserve(ticks);
    }
  }

  bool push(const TelemetryRecord& r) noexcept override {
    if (!r.has_sample) return true;
    plant_.measure(buffer_);
    auto& run = rec_.run;
    auto at = [&](int i) { return buffer_[static_cast<std::size_t>(i)]; };
    run.z_s.push_back(at(z_s_));
    run.z_s_ddot.push_back(at(z_s_ddot_));
    run.phi.push_back(at(phi_));
    run.phi_ddot.push_back(at(phi_ddot_));
    for (std::size_t i = 0; i < 2; ++i) {
      run.travel[i].push_back(at(travel_[i]));
      run.tyre_deflection[i].push_back(at(z_r_[i]) - at(z_u_[i]));
      run.force[i].push_back(r.command.value[i]);
      run.contact[i].push_back(at(contact_[i]));
      rec_.least_tyre_load[i] = std::min(rec_.least_tyre_load[i], at(tyre_[i]));
      rec_.peak_applied_force[i] = std::max(rec_.peak_applied_force[i], std::abs(at(applied_[i])));
    }
    if (keep_rows_) {
      rec_.t.push_back(static_cast<double>(r.sample.t_ns) * 1e-9);
      rec_.setpoint.push_back(r.controller.setpoint);
      rec_.command.emplace_back(r.command.value.begin(), r.command.value.begin() + static_cast<std::ptrdiff_t>(rec_.output_names.size()));
      rec_.truth.push_back(buffer_);
    }
    return true;
  }

 private:
  const SimulatedPlant& plant_;
  SuspensionRecording& rec_;
  bool keep_rows_;
  std::vector<double> buffer_;
  std::array<int, 2> z_r_{}, z_u_{}, travel_{}, contact_{}, tyre_{}, applied_{};
  int z_s_ = 0, z_s_ddot_ = 0, phi_ = 0, phi_ddot_ = 0;
};

std::string fixed(double v, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

std::string describe_road(const HalfCarParams& p) {
  std::ostringstream os;
  const auto& r = p.road;
  const char* plane = p.plane == HalfCarPlane::kPitch ? "pitch plane" : "roll plane";
  switch (r.kind) {
    case RoadKind::kFlat: os << "level road"; break;
    case RoadKind::kBump:
      os << "bump (eqs. 9-10) a0 " << r.bump.amplitude << " m, lambda0 " << r.bump.wavelength << " m, "
         << r.bump.cycles << (r.bump.cycles == 1.0 ? " hump" : " humps") << " at " << r.bump.start_time << " s";
      break;
    case RoadKind::kIso8608: {
      static const char* kClass[] = {"A", "B", "C", "D", "E"};
      os << "ISO 8608 class " << kClass[static_cast<int>(r.iso.road_class)] << " random road (seed " << r.iso.seed << ")";
      break;
    }
  }
  if (r.kind != RoadKind::kFlat && r.wheels != RoadWheels::kBoth) {
    os << (r.wheels == RoadWheels::kWheel1 ? " under wheel 1 only" : " under wheel 2 only");
  }
  if (p.plane == HalfCarPlane::kRoll && p.curve_radius != 0.0) {
    os << ", curve R " << p.curve_radius << " m from " << p.curve_start_time << " s";
  }
  os << ", V " << p.speed << " m/s, " << plane;
  return os.str();
}

double worse(const std::array<double, 2>& a) { return std::max(a[0], a[1]); }

// One reduction line: the paper's figure, then each active controller's.
struct ReductionRow {
  std::string key;    // JSON key
  std::string label;
  std::string paper;  // as the paper gives it, "" if it gives none
  double (*get)(const SuspensionMetrics&);
};

const std::vector<ReductionRow>& reduction_rows() {
  using M = SuspensionMetrics;
  static const std::vector<ReductionRow> rows{
      {"peak_body_displacement", "peak body displacement z_s", "74.2 %", [](const M& m) { return m.peak_z_s; }},
      {"peak_body_acceleration", "peak body acceleration z_s''", "88.72 %", [](const M& m) { return m.peak_acc; }},
      {"peak_tyre_deflection", "peak tyre deflection (worse wheel)", "28.5 %",
       [](const M& m) { return worse(m.peak_tyre_deflection); }},
      {"settling_time", "settling time", "41.7 % (6 -> 3.5 s)", [](const M& m) { return m.settling_time; }},
      {"wk_rms_body_acceleration", "Wk RMS body acceleration", "82.6 % (LQR)", [](const M& m) { return m.wk_rms_acc; }},
      {"rms_body_acceleration", "RMS body acceleration", "", [](const M& m) { return m.rms_acc; }},
      {"peak_suspension_travel", "peak suspension travel (worse)", "-56..-60 %",
       [](const M& m) { return worse(m.peak_travel); }},
      {"peak_angle", "peak pitch/roll angle", "", [](const M& m) { return m.peak_phi; }},
      {"peak_angle_acceleration", "peak pitch/roll acceleration", "65 % (roll)",
       [](const M& m) { return m.peak_phi_ddot; }},
      {"peak_jerk", "peak jerk", "", [](const M& m) { return m.peak_jerk; }},
  };
  return rows;
}

// Our reduction of a row against passive; NaN where it means nothing: the
// passive value is nil (the level road of a symmetric car has no heave), or
// the passive run never settled.
double row_reduction(const ReductionRow& row, const SuspensionMetrics& passive, const SuspensionMetrics& active) {
  const double a = row.get(passive), b = row.get(active);
  if (row.key == "settling_time" && !passive.settled) return std::numeric_limits<double>::quiet_NaN();
  if (!(std::abs(a) > 1e-12) || std::abs(a) < 1e-6 * std::abs(b)) return std::numeric_limits<double>::quiet_NaN();
  return reduction_percent(a, b);
}

std::string percent_text(double v) {
  if (!std::isfinite(v)) return "-";
  return fixed(v, 1) + " %";
}

// The bump's part of the account: why the tyre, the body and the settling
// differ from the paper's figures.
void explain_bump(const CompareResult& r, const HalfCarParams& p, double force_limit, std::ostream& out) {
  const auto& pas = r.metrics[0];
  const auto& fuz = r.metrics[1];
  const double hump_ms = 1e3 * p.road.bump.wavelength / p.speed;
  out << "* The bump: at V = " << p.speed << " m/s one hump of lambda0 = " << p.road.bump.wavelength
      << " m lasts " << fixed(hump_ms, 1) << " ms, a " << fixed(1e3 / hump_ms, 0)
      << " Hz event far above wheel hop (~10 Hz) and the body modes (~1.3-1.6 Hz). The tyre swallows it: the "
         "peak tyre deflection is "
      << fixed(1e3 * worse(pas.peak_tyre_deflection), 1) << " mm passive and "
      << fixed(1e3 * worse(fuz.peak_tyre_deflection), 1)
      << " mm fuzzy, set by the road before a force limited to " << fixed(force_limit, 0)
      << " N can move a wheel, so no controller here reproduces the paper's 28.5 % tyre reduction ("
      << percent_text(reduction_percent(worse(pas.peak_tyre_deflection), worse(fuz.peak_tyre_deflection)))
      << "). The paper's Figs. 2 and 6-27 are missing from its text, so its bump's real timing cannot be checked.\n";
  out << "* Body displacement: the impulse barely lifts the body (passive peak " << fixed(1e3 * pas.peak_z_s, 2)
      << " mm); the fuzzy controller takes " << percent_text(reduction_percent(pas.peak_z_s, fuz.peak_z_s))
      << " off it against the paper's 74.2 %. Its membership functions (Figs. 3-4) and the input and force "
         "scaling are not in the text: ours are stated choices in the config, not tuned to a result.\n";
  // When the passive peak comes, against the wheels' arrival at the bump.
  const auto& acc = r.runs[0].run.z_s_ddot;
  std::size_t k_peak = 0;
  for (std::size_t k = 0; k < acc.size(); ++k) {
    if (std::abs(acc[k]) > std::abs(acc[k_peak])) k_peak = k;
  }
  const double t_peak = static_cast<double>(k_peak) * r.runs[0].run.dt;
  const double arrival[2] = {p.road.bump.start_time,
                             p.road.bump.start_time + (p.plane == HalfCarPlane::kPitch && p.road.wheels == RoadWheels::kBoth
                                                           ? (p.dist_front + p.dist_rear) / p.speed
                                                           : 0.0)};
  const int wheel = (p.road.wheels == RoadWheels::kWheel2 || (p.road.wheels == RoadWheels::kBoth && t_peak >= arrival[1]))
                        ? 1 : 0;
  out << "* Body acceleration: the passive peak (" << fixed(pas.peak_acc, 2) << " m/s^2) comes "
      << fixed(1e3 * (t_peak - arrival[wheel]), 1) << " ms after wheel " << wheel + 1
      << " reaches the bump: the humps' impulse reaches the body through the spring and damper within a few "
         "loop periods (2.5 ms), and the controllers push on the body with at most "
      << fixed(force_limit, 0) << " N; they cannot stop the wheel. Fuzzy takes "
      << percent_text(reduction_percent(pas.peak_acc, fuz.peak_acc)) << " off the peak, "
      << percent_text(reduction_percent(pas.rms_acc, fuz.rms_acc)) << " off the RMS and "
      << percent_text(reduction_percent(pas.wk_rms_acc, fuz.wk_rms_acc))
      << " off the Wk-weighted RMS, against the paper's 88.72 % (peak).\n";
  out << "* Settling: the paper gives no band; ours is +-" << fixed(1e3 * r.settling_band, 3)
      << " mm (a fixed share of the passive peak) for every run. Passive settles in "
      << fixed(pas.settling_time, 2) << " s (paper 6 s), fuzzy in " << fixed(fuz.settling_time, 2)
      << " s (paper 3.5 s).\n";
}

// The curve's part: the steady roll each controller leaves.
void explain_curve(const CompareResult& r, const HalfCarParams& p, std::ostream& out) {
  const auto& pas = r.metrics[0];
  const auto& fuz = r.metrics[1];
  const auto& types = suspension_controller_types();
  out << "* Curve: the centrifugal roll moment (" << fixed(half_car_roll_moment(p), 0)
      << " N m) is a steady load. Roll angle at the end of the run:";
  for (std::size_t k = 0; k < r.runs.size(); ++k) {
    out << (k ? ", " : " ") << types[k] << " " << fixed(1e3 * r.runs[k].run.phi.back(), 1) << " mrad";
  }
  out << "; peak: passive " << fixed(1e3 * pas.peak_phi, 1) << ", fuzzy " << fixed(1e3 * fuz.peak_phi, 1)
      << " mrad. Fuzzy and skyhook act on body corner velocity and acceleration only: they damp the roll "
         "transient but leave the steady roll to the springs.";
  const auto& lqr = r.runs[3].run;
  if (std::abs(lqr.phi.back()) > 1.05 * std::abs(r.runs[0].run.phi.back())) {
    out << " LQR regulates the wheel displacements to zero as well (the tyre deflection on a level road), but in "
           "a curve the load transfer fixes the tyre deflections, so it drives the actuators to "
        << fixed(lqr.force[0].back(), 0) << " / " << fixed(lqr.force[1].back(), 0)
        << " N and rolls the body further: a limit of that state choice (no load-transfer or road state, no "
           "integral action), reported as it is.";
  }
  out << "\n";
}

// The account of the differences, with this run's numbers in it.
void explain(const CompareResult& r, const HalfCarParams& p, double force_limit, const FuzzyEngineSpec& fuzzy,
             std::ostream& out) {
  const auto& pas = r.metrics[0];
  const auto& fuz = r.metrics[1];
  const bool paper_bump = p.road.kind == RoadKind::kBump && p.road.wheels == RoadWheels::kBoth &&
                          p.plane == HalfCarPlane::kPitch;
  out << "\nWhy our figures differ from the paper's:\n";
  if (!paper_bump) {
    out << "* The paper's figures are for its bump in the pitch plane; this run is a " << describe_road(p)
        << ", so the paper's column is for orientation only.\n";
  }
  if (p.road.kind == RoadKind::kBump) explain_bump(r, p, force_limit, out);
  if (pas.rms_jerk > 1e-6 && fuz.rms_jerk > 1.2 * pas.rms_jerk) {
    const auto& in1 = fuzzy.inputs[0];
    out << "* Jerk: the fuzzy law is steep (its whole force range over +-" << fixed(in1.max / in1.scale, 3)
        << " of its first input, " << in1.name << "), so it also passes the transducer noise into the force: RMS jerk "
        << fixed(fuz.rms_jerk, 1) << " m/s^3 against " << fixed(pas.rms_jerk, 1)
        << " passive (the paper reports less jerk with its controller).\n";
  }
  if (p.plane == HalfCarPlane::kRoll && p.curve_radius != 0.0) explain_curve(r, p, out);
  out << "* The vehicle: Table 1 mixes a full car (M = 2160 kg, I_y = 4140, I_x = 946 kg m^2) with half-car "
         "equations; we simulate half of it (docs/rig-models.md 3.4.1) with springs and dampers inside Table 2. The "
         "paper's LQR figures (Wk RMS 0.2834 -> 0.0492 m/s^2) are quoted for its own LQR design, whose weights "
         "it does not give";
  if (pas.wk_rms_acc > 1e-6) {
    out << "; ours: " << fixed(pas.wk_rms_acc, 4) << " -> " << fixed(r.metrics[3].wk_rms_acc, 4) << " m/s^2";
  }
  out << ".\n";
}

}  // namespace

double half_car_disturbance_start(const HalfCarParams& p) {
  if (p.plane == HalfCarPlane::kRoll && p.curve_radius != 0.0 && p.road.kind == RoadKind::kFlat) {
    return p.curve_start_time;
  }
  if (p.road.kind == RoadKind::kBump) return p.road.bump.start_time;
  return 0.0;
}

SuspensionRecording run_half_car(const RigConfig& config, ControllerKind controller_type, double duration_s,
                                 bool keep_rows) {
  if (config.rig != RigKind::kHalfCar) {
    throw std::runtime_error("this command is for the half_car rig, not " + std::string(to_string(config.rig)));
  }
  if (!is_simulated(config.driver)) {
    throw std::runtime_error("this command runs the simulated rig: '" + std::string(to_string(config.driver)) +
                             "' would drive hardware");
  }
  RigConfig c = config;
  c.controller.type = controller_type;
  AssembledRig rig = assemble_rig(c);
  auto* sim = dynamic_cast<SimDriver*>(rig.driver.get());
  if (sim == nullptr) throw std::runtime_error("the half car comparison needs the simulated driver");

  SuspensionRecording rec;
  rec.controller = to_string(controller_type);
  for (const auto& s : rig.driver->layout().inputs) rec.signal_names.push_back(s.name);
  for (const auto& s : rig.driver->layout().outputs) rec.output_names.push_back(s.name);
  rec.setpoint_name = rig.setpoint_name;

  LoopOptions options;
  options.period_ns = std::llround(c.loop.period_s * 1e9);
  options.overrun_policy = c.loop.overrun_policy;
  options.max_ticks = std::llround(duration_s / c.loop.period_s);
  options.timing_every_ticks = std::max<int64_t>(1, std::llround(c.loop.timing_publish_s / c.loop.period_s));
  options.start_from_input = rig.profile_start_input;
  if (options.max_ticks < 1) throw std::runtime_error("run duration must be at least one period");

  RecordingSink sink(sim->plant(), rec, static_cast<std::size_t>(options.max_ticks) + 1, keep_rows);
  VirtualClock clock;
  rig.driver->start();
  // The rig as `rigctl run --fast` runs it: the configured detectors and
  // state machine, the automatic sequence (no operator here).
  rig.safety.auto_sequence = true;
  RigLoop loop(*rig.driver, *rig.controller, *rig.profile, rig.detectors, sink, clock, options, rig.safety);
  const std::atomic<bool> stop{false};
  rec.loop = loop.run(stop);
  rig.driver->stop();

  rec.run.dt = c.loop.period_s;
  rec.run.disturbance_start = half_car_disturbance_start(c.half_car);
  return rec;
}

void write_recording_csv(const SuspensionRecording& rec, const std::string& path, const std::string& note) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (f == nullptr) throw std::runtime_error(path + ": cannot create");
  std::fprintf(f, "# rig: half_car\n");
  if (rec.run.dt > 0.0) std::fprintf(f, "# sample_rate_hz: %ld\n", std::lround(1.0 / rec.run.dt));
  std::fprintf(f, "# controller: %s\n", rec.controller.c_str());
  std::fprintf(f, "# note: %s\n", note.c_str());
  std::fprintf(f, "t,%s", rec.setpoint_name.c_str());
  for (const auto& n : rec.output_names) std::fprintf(f, ",%s", n.c_str());
  for (const auto& n : rec.signal_names) std::fprintf(f, ",%s", n.c_str());
  std::fputc('\n', f);
  for (std::size_t k = 0; k < rec.t.size(); ++k) {
    std::fprintf(f, "%.12g,%.9g", rec.t[k], rec.setpoint[k] + 0.0);
    for (double v : rec.command[k]) std::fprintf(f, ",%.9g", v + 0.0);
    for (double v : rec.truth[k]) std::fprintf(f, ",%.9g", v + 0.0);
    std::fputc('\n', f);
  }
  const bool bad = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || bad) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": write failed");
  }
  fs::rename(tmp, path);
}

namespace {

// What one comparison runs: the config, checked for `compare`, and its settings.
struct CompareSetup {
  const CompareOptions& options;
  RigConfig config;
  double duration = 0.0;     // [s] simulated per run
  double force_limit = 0.0;  // [N] per actuator
  const HalfCarParams& car() const { return config.half_car; }
};

CompareSetup load_compare_setup(const CompareOptions& options) {
  CompareSetup s{options, load_rig_config(options.config_path, options.case_name)};
  if (s.config.rig != RigKind::kHalfCar) {
    throw ConfigError(options.config_path + ": rig: `rigctl compare` is for the half_car rig, this config is " +
                      std::string(to_string(s.config.rig)));
  }
  s.duration = s.config.profile.type == ProfileKind::kHold ? s.config.profile.duration_s : 0.0;
  if (!(s.duration > 0.0)) {
    throw ConfigError(options.config_path + ": profile.type: `rigctl compare` needs a `hold` profile (the body held at rest)");
  }
  s.force_limit = s.config.controller.suspension.force_limit;
  return s;
}

std::string compare_out_dir(const CompareSetup& s) {
  const CompareOptions& o = s.options;
  if (!o.out_dir.empty()) return o.out_dir;
  return (fs::path(s.config.telemetry.log_dir) / ("half_car-compare" + (o.case_name.empty() ? "" : "-" + o.case_name)))
      .string();
}

// --- Computing: the four runs and their metrics.

// Runs every suspension controller (on_run hears each as it ends), then
// measures all against one settling band: a share of the passive run's peak.
void compute_compare(const CompareSetup& s, CompareResult& result,
                     const std::function<void(ControllerKind, const SuspensionRecording&)>& on_run) {
  for (const ControllerKind controller : suspension_controllers()) {
    result.runs.push_back(run_half_car(s.config, controller, s.duration));
    on_run(controller, result.runs.back());
  }
  const SuspensionMetrics passive_own = compute_suspension_metrics(result.runs[0].run);
  const auto& rep = s.config.suspension_report;
  result.settling_band = std::max(rep.settling_band_fraction * passive_own.peak_z_s, rep.settling_min_band);
  SettlingSpec settling;
  settling.fraction = 0.0;
  settling.min_band = result.settling_band;
  for (const auto& rec : result.runs) result.metrics.push_back(compute_suspension_metrics(rec.run, settling));
}

// --- Reporting: the text, the CSV files, the JSON.

void print_compare_header(const CompareSetup& s, std::ostream& out) {
  const CompareOptions& o = s.options;
  out << "rigctl compare: half_car from " << o.config_path << (o.case_name.empty() ? "" : " case " + o.case_name)
      << "\n"
      << "  road: " << describe_road(s.car()) << "; " << s.duration << " s simulated, loop "
      << s.config.loop.period_s * 1e3 << " ms, force limit " << s.force_limit << " N per actuator\n";
  out.flush();
}

void write_compare_csvs(const CompareSetup& s, CompareResult& result) {
  const CompareOptions& o = s.options;
  const std::string source = "rigctl compare " + o.config_path + (o.case_name.empty() ? "" : " --case " + o.case_name) +
                             ": plant truth (noise-free); the loop ran on the sensor models; f_1, f_2 as commanded";
  for (const auto& rec : result.runs) {
    const std::string path = (fs::path(result.out_dir) / (rec.controller + ".csv")).string();
    write_recording_csv(rec, path, source);
    result.csv_paths.push_back(path);
  }
}

// The metrics table, our reductions beside the paper's, the settling times.
void print_metrics(const CompareSetup& s, const CompareResult& result, std::ostream& out) {
  const auto& types = suspension_controller_types();
  out << "\nMetrics (plant truth; settling band +-" << fixed(1e3 * result.settling_band, 3) << " mm = "
      << fixed(100.0 * s.config.suspension_report.settling_band_fraction, 1)
      << " % of the passive peak, the same for every run):\n"
      << format_metrics_table(types, result.metrics);
  out << "\nReductions against passive (positive = smaller than passive), ours beside the paper's (its fuzzy "
         "controller unless marked):\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-36s %20s", "metric", "paper");
  out << line;
  for (std::size_t k = 1; k < types.size(); ++k) {
    std::snprintf(line, sizeof line, "%10s", types[k].c_str());
    out << line;
  }
  out << "\n";
  for (const auto& row : reduction_rows()) {
    std::snprintf(line, sizeof line, "%-36s %20s", row.label.c_str(), row.paper.empty() ? "-" : row.paper.c_str());
    out << line;
    for (std::size_t k = 1; k < types.size(); ++k) {
      std::snprintf(line, sizeof line, "%10s",
                    percent_text(row_reduction(row, result.metrics[0], result.metrics[k])).c_str());
      out << line;
    }
    out << "\n";
  }
  out << "(paper: \"suspension travel improves by 56-60 %\" and \"active suspension travel increases by 56-60 %\": "
         "its text says both; -56..-60 % reads it as more travel.)\n";
  const PaperFigures paper;
  out << "Settling time [s]: paper passive " << paper.settling_passive_s << ", active " << paper.settling_active_s
      << "; ours";
  for (std::size_t k = 0; k < types.size(); ++k) {
    out << " " << types[k] << " " << fixed(result.metrics[k].settling_time, 2)
        << (result.metrics[k].settled ? "" : " (not settled)");
  }
  out << "\n";
}

// Forces and contact: the checks, stated.
void print_forces_and_contact(const CompareSetup& s, const CompareResult& result, std::ostream& out) {
  const auto& types = suspension_controller_types();
  double largest_force = 0.0;
  for (std::size_t k = 0; k < result.runs.size(); ++k) {
    largest_force = std::max(largest_force, worse(result.metrics[k].peak_force));
  }
  out << "Actuator forces: largest " << fixed(largest_force, 0) << " N of the " << fixed(s.force_limit, 0)
      << " N limit (" << (largest_force <= s.force_limit ? "within" : "EXCEEDED") << ").\n";
  bool lost = false;
  for (std::size_t k = 0; k < result.runs.size(); ++k) {
    const auto& m = result.metrics[k];
    if (m.time_without_contact[0] > 0.0 || m.time_without_contact[1] > 0.0) {
      lost = true;
      out << "Tyre contact LOST: " << types[k] << ": wheel 1 " << fixed(m.time_without_contact[0], 3) << " s, wheel 2 "
          << fixed(m.time_without_contact[1], 3) << " s without contact.\n";
    }
  }
  if (lost) return;
  out << "Tyre contact: kept by both wheels in every run (least tyre load";
  for (std::size_t k = 0; k < result.runs.size(); ++k) {
    out << (k ? "; " : " ") << types[k] << " " << fixed(result.runs[k].least_tyre_load[0], 0) << "/"
        << fixed(result.runs[k].least_tyre_load[1], 0) << " N";
  }
  out << ").\n";
}

std::string json_pair(const std::array<double, 2>& a) {
  return "[" + json_number(a[0]) + ", " + json_number(a[1]) + "]";
}

// One run's entry of metrics.json (without the separator after it).
void write_run_json(std::ostream& js, const std::string& type, const std::string& csv_path,
                    const SuspensionRecording& rec, const SuspensionMetrics& m) {
  const std::pair<const char*, std::string> fields[] = {
      {"csv", json_string(fs::path(csv_path).filename().string())},
      {"final_state", json_string(std::string(to_string(rec.loop.final_state)))},
      {"ticks", std::to_string(rec.loop.ticks)},
      {"peak_z_s_m", json_number(m.peak_z_s)},
      {"rms_z_s_m", json_number(m.rms_z_s)},
      {"peak_acc_m_s2", json_number(m.peak_acc)},
      {"rms_acc_m_s2", json_number(m.rms_acc)},
      {"wk_rms_acc_m_s2", json_number(m.wk_rms_acc)},
      {"settling_time_s", json_number(m.settling_time)},
      {"settled", m.settled ? "true" : "false"},
      {"peak_jerk_m_s3", json_number(m.peak_jerk)},
      {"rms_jerk_m_s3", json_number(m.rms_jerk)},
      {"peak_travel_m", json_pair(m.peak_travel)},
      {"peak_tyre_deflection_m", json_pair(m.peak_tyre_deflection)},
      {"peak_force_n", json_pair(m.peak_force)},
      {"peak_applied_force_n", json_pair(rec.peak_applied_force)},
      {"time_without_contact_s", json_pair(m.time_without_contact)},
      {"least_tyre_load_n", json_pair(rec.least_tyre_load)},
      {"peak_phi_rad", json_number(m.peak_phi)},
      {"peak_phi_ddot_rad_s2", json_number(m.peak_phi_ddot)},
      {"rms_phi_ddot_rad_s2", json_number(m.rms_phi_ddot)},
  };
  js << "    " << json_string(type) << ": {\n";
  const std::size_t n = std::size(fields);
  for (std::size_t i = 0; i < n; ++i) {
    js << "      \"" << fields[i].first << "\": " << fields[i].second << (i + 1 < n ? ",\n" : "\n");
  }
  js << "    }";
}

void write_reductions_json(std::ostream& js, const CompareResult& result) {
  const auto& types = suspension_controller_types();
  const auto& rows = reduction_rows();
  for (std::size_t k = 1; k < types.size(); ++k) {
    js << "    " << json_string(types[k]) << ": {";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      js << (i ? ", " : "") << json_string(rows[i].key) << ": "
         << json_number(row_reduction(rows[i], result.metrics[0], result.metrics[k]));
    }
    js << "}" << (k + 1 < types.size() ? "," : "") << "\n";
  }
}

void write_paper_json(std::ostream& js) {
  const PaperFigures paper;
  js << "{\"peak_body_displacement_reduction_percent\": " << json_number(paper.peak_body_displacement_reduction)
     << ", \"peak_body_acceleration_reduction_percent\": " << json_number(paper.peak_body_acceleration_reduction)
     << ", \"peak_tyre_deflection_reduction_percent\": " << json_number(paper.peak_tyre_deflection_reduction)
     << ", \"settling_passive_s\": " << json_number(paper.settling_passive_s)
     << ", \"settling_active_s\": " << json_number(paper.settling_active_s)
     << ", \"roll_acceleration_reduction_percent\": " << json_number(paper.roll_acceleration_reduction)
     << ", \"lqr_wk_rms_passive_m_s2\": " << json_number(paper.lqr_wk_passive)
     << ", \"lqr_wk_rms_active_m_s2\": " << json_number(paper.lqr_wk_active) << "}";
}

void write_metrics_json(const CompareSetup& s, CompareResult& result) {
  const HalfCarParams& p = s.car();
  const auto& types = suspension_controller_types();
  result.json_path = (fs::path(result.out_dir) / "metrics.json").string();
  std::ofstream js(result.json_path);
  if (!js) throw std::runtime_error(result.json_path + ": cannot create");
  js << "{\n  \"rig\": \"half_car\",\n  \"config\": " << json_string(s.options.config_path)
     << ",\n  \"case\": " << json_string(s.options.case_name) << ",\n  \"road\": " << json_string(describe_road(p))
     << ",\n  \"plane\": \"" << (p.plane == HalfCarPlane::kPitch ? "pitch" : "roll") << "\""
     << ",\n  \"duration_s\": " << json_number(s.duration) << ",\n  \"force_limit_n\": " << json_number(s.force_limit)
     << ",\n  \"settling_band_m\": " << json_number(result.settling_band) << ",\n  \"runs\": {\n";
  for (std::size_t k = 0; k < result.runs.size(); ++k) {
    write_run_json(js, types[k], result.csv_paths[k], result.runs[k], result.metrics[k]);
    js << (k + 1 < result.runs.size() ? "," : "") << "\n";
  }
  js << "  },\n  \"reductions_percent\": {\n";
  write_reductions_json(js, result);
  js << "  },\n  \"paper\": ";
  write_paper_json(js);
  js << "\n}\n";
  js.close();
  if (!js) throw std::runtime_error(result.json_path + ": write failed");
}

}  // namespace

// The comparison's story: set up, run and measure, then report.
CompareResult run_compare(const CompareOptions& options, std::ostream& out) {
  const CompareSetup setup = load_compare_setup(options);
  CompareResult result;
  result.out_dir = compare_out_dir(setup);
  fs::create_directories(result.out_dir);
  print_compare_header(setup, out);

  compute_compare(setup, result, [&out](ControllerKind controller, const SuspensionRecording& rec) {
    out << "  " << std::left << std::setw(8) << controller << std::right << " " << rec.loop.ticks << " ticks, "
        << to_string(rec.loop.final_state) << "\n";
    out.flush();
  });

  write_compare_csvs(setup, result);
  print_metrics(setup, result, out);
  print_forces_and_contact(setup, result, out);
  explain(result, setup.car(), setup.force_limit, setup.config.controller.suspension.fuzzy, out);
  write_metrics_json(setup, result);

  out << "\n  csv: " << result.out_dir << "/{passive,fuzzy,skyhook,lqr}.csv\n  metrics: " << result.json_path << "\n";
  out.flush();
  return result;
}

}  // namespace rigctl
