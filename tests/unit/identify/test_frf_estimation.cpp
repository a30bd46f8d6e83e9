// The parts of rigctl identify and tune on known signals and systems: the
// excitation, Welch's estimate, the FRF under feedback, the FRF file, the
// margins, the PI design and the tuned config's text edit.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "config_edit.hpp"
#include "tools/identify/excitation.hpp"
#include "tools/identify/frf_estimate.hpp"
#include "tools/identify/frf_file.hpp"
#include "tools/tune/loop_design.hpp"
#include "tools/tune/relay_experiment.hpp"
#include "tools/tune/tuned_config.hpp"

namespace rigctl {
namespace {

using C = std::complex<double>;
constexpr double kT = 0.0025;

ExcitationSpec spec(ExcitationKind kind) {
  ExcitationSpec s;
  s.kind = kind;
  s.band_min_hz = 0.5;
  s.band_max_hz = 30.0;
  s.amplitude = 0.003;
  s.duration_s = 10.0;
  s.resolution_hz = 0.5;
  s.period_s = kT;
  return s;
}

TEST(Excitation, PeakIsTheAmplitudeAndTheMultisineLivesOnItsOddLines) {
  for (auto kind : {ExcitationKind::kMultisine, ExcitationKind::kChirp, ExcitationKind::kPinkNoise}) {
    const Excitation e = make_excitation(spec(kind));
    double peak = 0.0;
    for (double v : e.values) peak = std::max(peak, std::abs(v));
    EXPECT_NEAR(peak, 0.003, 1e-15) << to_string(kind);
    EXPECT_EQ(e.segment_ticks, 800U);
  }
  const Excitation e = make_excitation(spec(ExcitationKind::kMultisine));
  EXPECT_TRUE(e.periodic);
  EXPECT_EQ(e.lines.front(), 1U);  // 0.5 Hz: the band's low end is kept
  for (std::size_t k : e.lines) {
    EXPECT_EQ(k % 2, 1U);
    EXPECT_LE(static_cast<double>(k) * 0.5, 30.0);
  }
  EXPECT_NEAR(static_cast<double>(e.lines.size()), 20.0, 1.0);  // 30 odd bins, one in three left out
  for (std::size_t i = 0; i + 800 < e.values.size(); ++i) ASSERT_EQ(e.values[i], e.values[i + 800]);
  // All its power on the lines.
  const std::span<const double> x(e.values);
  const CrossSpectra s = welch({x}, WelchSettings{800, 800, SpectralWindow::kRectangular, 400.0});
  double on = 0.0, off = 0.0;
  for (std::size_t k = 1; k < s.frequency_hz.size(); ++k) {
    (std::find(e.lines.begin(), e.lines.end(), k) != e.lines.end() ? on : off) += s.power(k, 0);
  }
  EXPECT_LT(off, 1e-20 * on);
}

TEST(Excitation, ABandBeyondNyquistIsRefusedByName) {
  ExcitationSpec s = spec(ExcitationKind::kMultisine);
  s.band_max_hz = 250.0;
  EXPECT_THROW(
      {
        try {
          make_excitation(s);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("excitation band"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
}

// G(z) = 0.02 z^-1 / (1 - 0.95 z^-1): a lagging plant in a loop
// u = 3 (r - y - n), y = G u + n with sensor noise n fed back.
struct Loop {
  std::vector<double> r, u, y;
};

Loop simulate_loop(const std::vector<double>& r, double noise_sd) {
  Loop l{r, {}, {}};
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, noise_sd);
  double x = 0.0, u_prev = 0.0;
  for (double rk : r) {
    x = 0.95 * x + 0.02 * u_prev;
    const double y = x + noise(rng);
    const double u = 3.0 * (rk - y);
    l.u.push_back(u);
    l.y.push_back(y);
    u_prev = u;
  }
  return l;
}

C plant(double f) {
  const C zi = std::polar(1.0, -2.0 * std::numbers::pi * f * kT);
  return 0.02 * zi / (1.0 - 0.95 * zi);
}

TEST(FrfEstimate, DemandAsInstrumentRecoversThePlantAndTheClosedLoopUnderFeedback) {
  ExcitationSpec x = spec(ExcitationKind::kMultisine);
  x.duration_s = 120.0;  // 59 averages: the instrument's scatter well below the direct ratio's bias
  const Excitation e = make_excitation(x);
  const Loop l = simulate_loop(e.values, 1e-4);
  const std::size_t from = e.segment_ticks;
  const std::size_t n = l.r.size() - from;
  FrfData out;
  out.command = {"u", "1"};
  out.responses = {{"y", "m"}};
  const IdentificationRecord rec{std::span<const double>(l.r).subspan(from, n), std::span<const double>(l.u).subspan(from, n),
                                 {std::span<const double>(l.y).subspan(from, n)}};
  estimate_frf(rec, WelchSettings{800, 800, SpectralWindow::kRectangular, 400.0}, 0.5, 30.0, e.lines, out);
  ASSERT_EQ(out.frequency_hz.size(), e.lines.size());
  // The direct ratio S_uy / S_uu: the fed-back noise pulls it towards -1/C.
  const CrossSpectra s = welch({rec.command, rec.responses[0]}, WelchSettings{800, 800, SpectralWindow::kRectangular, 400.0});
  double mean_iv = 0.0, mean_direct = 0.0;
  int compared = 0;
  for (std::size_t i = 0; i < out.frequency_hz.size(); ++i) {
    const double f = out.frequency_hz[i];
    if (f > 10.0) continue;  // above, the plant's output sinks into the noise
    ++compared;
    mean_iv += std::abs(out.plant[0].value[i] / plant(f) - 1.0) ;
    const std::size_t k = e.lines[i];
    mean_direct += std::abs(s.at(k, 0, 1) / s.power(k, 0) / plant(f) - 1.0) ;
    // The closed loop is T = C G / (1 + C G).
    const C t = 3.0 * plant(f) / (1.0 + 3.0 * plant(f));
    EXPECT_LT(std::abs(out.closed_loop[0].value[i] / t - 1.0), 0.25) << f;
  }
  mean_iv /= compared;
  mean_direct /= compared;
  EXPECT_LT(mean_iv, 0.03);
  // The direct ratio S_uy / S_uu is pulled by the fed-back noise (towards
  // -1/C): never closer than the instrument's estimate.
  EXPECT_GT(mean_direct, mean_iv);
}

TEST(FrfFile, RoundTripsAndNamesAMissingKey) {
  FrfData f;
  f.rig = "quarter_car";
  f.config = "c.yaml";
  f.sample_rate_hz = 400.0;
  f.demand = {"x_ref", "m"};
  f.command = {"u", "1"};
  f.responses = {{"x_r", "m"}};
  f.controller_type = "pi";
  f.controller_gains = {{"kp", 20.0}, {"ki", 0.0}};
  f.excitation.kind = "multisine";
  f.estimation.window = "rectangular";
  f.frequency_hz = {0.5, 1.5};
  f.closed_loop = {{"x_r", {C(0.5, -0.5), C(0.1, -0.2)}, {0.99, 0.98}}};
  f.plant = {{"x_r", {C(0.01, -0.07), C(0.001, -0.02)}, {0.97, 0.96}}};
  f.command_coherence = {0.99, 0.99};
  f.noise_floor = {{"x_r", {1e-12, 2e-12}}, {"u", {1e-9, 1e-9}}};
  f.response_psd = {{"x_r", {1e-6, 1e-7}}, {"u", {1e-3, 1e-3}}};
  const std::string text = frf_to_json(f);
  const FrfData back = parse_frf_json(text, "t.json");
  EXPECT_EQ(back.plant_of("x_r").value[1], f.plant[0].value[1]);
  EXPECT_EQ(back.closed_loop[0].coherence[0], 0.99);
  EXPECT_EQ(back.controller_gains.at("kp"), 20.0);
  const std::string broken = test::edit(text, "\"command_coherence\"", "\"command_coherenz\"");
  try {
    parse_frf_json(broken, "t.json");
    FAIL() << "accepted a file without command_coherence";
  } catch (const FrfFileError& e) {
    EXPECT_EQ(std::string(e.what()), "t.json: command_coherence: missing");
  }
}

// L(s) = 1 / (s (1 + s)): crossover at sqrt((sqrt 5 - 1) / 2) rad/s, phase
// margin 90 - atan(that) = 51.83 degrees.
TEST(Margins, MatchTheTextbookLoop) {
  std::vector<double> f;
  std::vector<C> l;
  for (int i = 0; i <= 400; ++i) {
    const double hz = 0.01 * std::pow(100.0, i / 400.0);
    const C s(0.0, 2.0 * std::numbers::pi * hz);
    f.push_back(hz);
    l.push_back(1.0 / (s * (1.0 + s)));
  }
  const Margins m = loop_margins(f, l);
  const double wc = std::sqrt((std::sqrt(5.0) - 1.0) / 2.0);
  EXPECT_NEAR(m.crossover_hz, wc / (2.0 * std::numbers::pi), 1e-4);
  EXPECT_NEAR(m.phase_margin_deg, 90.0 - std::atan(wc) * 180.0 / std::numbers::pi, 0.05);
  EXPECT_TRUE(m.gain_margin_beyond_band);  // never reaches -180
}

TEST(PiDesign, PutsTheLoopAtTheTargetPhaseMargin) {
  PlantResponse p;
  for (int i = 0; i <= 60; ++i) {
    const double hz = 0.5 * std::pow(60.0, i / 60.0);
    const C s(0.0, 2.0 * std::numbers::pi * hz);
    p.frequency_hz.push_back(hz);
    p.position.push_back(0.22 / (s * (1.0 + 0.004 * s)) * std::exp(-s * 0.5 * kT));
    p.coherence.push_back(1.0);
  }
  const PlantGrid grid(p);
  LoopGains base;
  base.kind = ControllerKind::kPi;
  for (double pm : {45.0, 60.0}) {
    DesignTarget t;
    t.phase_margin_deg = pm;
    const LoopDesign d = design_loop(grid, base, t);
    EXPECT_TRUE(d.meets_target) << d.note;
    EXPECT_NEAR(d.margins.phase_margin_deg, pm, 0.5);
    EXPECT_GT(d.gains.ki, 0.0);
    t.crossover_hz = 5.0;
    const LoopDesign at5 = design_loop(grid, base, t);
    EXPECT_NEAR(at5.margins.crossover_hz, 5.0, 0.05);
    EXPECT_NEAR(at5.margins.phase_margin_deg, pm, 0.5);
  }
}

TEST(ZieglerNichols, FollowsTheRules) {
  LoopGains pi;
  pi.kind = ControllerKind::kPi;
  const LoopGains g = ziegler_nichols(pi, 100.0, 0.05);
  EXPECT_DOUBLE_EQ(g.kp, 45.0);
  EXPECT_DOUBLE_EQ(g.ki, 45.0 / (0.05 / 1.2));
  LoopGains pvp;
  pvp.kind = ControllerKind::kPvp;
  const LoopGains h = ziegler_nichols(pvp, 10.0, 0.8);
  EXPECT_DOUBLE_EQ(h.ke, 6.0);
  EXPECT_DOUBLE_EQ(h.kv, 6.0 * 0.8 / 8.0);
}

TEST(TunedConfig, ChangesOnlyTheGainValues) {
  const std::string before = test::shipped_config();
  const std::string after = with_controller_values(before, {{"kp", 123.5}, {"ki", 456.0}}, "tuned.yaml");
  EXPECT_NE(after.find("  kp: 123.5                   # [1/m] chosen (paper gives none): loop crossover ~4 Hz"), std::string::npos);
  EXPECT_NE(after.find("  ki: 456.0                   # [1/(m s)]"), std::string::npos);
  // Everything else as it was, line for line.
  EXPECT_EQ(test::edit(test::edit(after, "kp: 123.5 ", "kp: 80.0 "), "ki: 456.0 ", "ki: 60.0 "), before);
}

}  // namespace
}  // namespace rigctl

namespace rigctl {
namespace {

std::string config_error(const std::string& yaml) {
  try {
    parse_rig_config(yaml, "bad.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(IdentifyConfig, ReadsTheSectionAndNamesABadKey) {
  const RigConfig c = parse_rig_config(test::shipped_config(), "q.yaml");
  EXPECT_EQ(c.identify.excitation, ExcitationKind::kMultisine);
  EXPECT_EQ(c.identify.resolution_hz, 0.5);
  ASSERT_TRUE(c.identify.amplitude.has_value());
  EXPECT_EQ(*c.identify.amplitude, 0.0025);
  EXPECT_NE(config_error(test::edit(test::shipped_config(), "band_hz: \\[0.5, 30.0\\]", "band_hz: [30.0, 0.5]"))
                .find("identify.band_hz: must be [low, high]"),
            std::string::npos);
  EXPECT_NE(config_error(test::edit(test::shipped_config(), "excitation: multisine", "excitation: sweep"))
                .find("identify.excitation: unknown excitation 'sweep' (known: multisine, chirp, pink_noise)"),
            std::string::npos);
  EXPECT_NE(config_error(test::edit(test::shipped_config(), "  settle_s: 2.0", "  settle_s: 2.0\n  settle: 1.0")).find("identify.settle"),
            std::string::npos);
}

}  // namespace
}  // namespace rigctl
