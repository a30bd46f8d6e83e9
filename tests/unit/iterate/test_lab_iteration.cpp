// The iteration on a lab's target (issue 29), on a linear rig made of the
// model's own frequency response with an error the model does not know
// (so no simulation is needed): the test part is found, the drive starts
// at home with the target, the first pass plays at half level, the gain
// adapts from what was measured, the prediction is corrected by what the
// rig did, and a drive that grows too much is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "config/config_reader.hpp"
#include "tools/identify/plant_linearisation.hpp"
#include "tools/iterate/drive_iteration.hpp"
#include "tools/iterate/gain_adaptation.hpp"
#include "tools/iterate/spectrum.hpp"
#include "tools/iterate/test_window.hpp"

namespace rigctl {
namespace {

constexpr double kDt = 0.0025;

// Home, a 3.5 s ramp to mid-stroke, 15 s of sines with a 1/f amplitude
// (0.7-12 Hz) from 5 s, back home over 2.5 s from 20.5 s.
std::vector<double> lab_target() {
  std::vector<double> x;
  for (double t = 0.0; t < 23.0 - 1e-9; t += kDt) {
    const double up = std::clamp((t - 1.0) / 3.5, 0.0, 1.0), down = std::clamp((t - 20.5) / 2.5, 0.0, 1.0);
    double v = 0.08 * (0.5 - 0.5 * std::cos(std::numbers::pi * up)) * (0.5 + 0.5 * std::cos(std::numbers::pi * down));
    if (t > 5.0 && t < 20.0) {
      const double fade = std::min({1.0, t - 5.0, 20.0 - t});
      for (double f = 0.7; f <= 12.0; f += 0.5) v += fade * 0.0008 / f * std::sin(2 * std::numbers::pi * f * t + 3 * f);
    }
    x.push_back(v);
  }
  return x;
}

struct LinearRig {
  RigConfig config;
  IterationRig rig;
  std::complex<double> error;  // the rig's response over the model's, in the band (0.5-30 Hz)
  int played = 0;

  explicit LinearRig(std::complex<double> rig_over_model) : error(rig_over_model) {
    config = load_rig_config(std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml");
    config.controller.pi.velocity_feedforward = 0.0;
    const auto freqs = model_frequencies(0.05, 31.0);
    rig.config = &config;
    rig.operating_point = 0.08;
    rig.command_hold = linearise_quarter_car(config.quarter_car, 0.08, {"x_r"}).command;
    rig.channel = drive_frf_from_model(config, "x_w", 0.08, freqs, "nominal model");
    rig.paths = loop_paths_from_model(config, 0.08, freqs, "nominal model");
    rig.play = [this](const std::vector<double>& drive, int) {
      ++played;
      PlayResult r;
      r.completed = true;
      const auto response = [&](const DriveFrf& h, std::complex<double> rest, std::complex<double> scale) {
        // The model's error lies in the band; below it the rig follows slow motion as the model says.
        return filtered(drive, kDt, [&](double f) { return f > 0.0 ? (f >= 0.5 ? scale : 1.0) * h.at(f) : rest; });
      };
      r.response = response(rig.channel, 1.0, error);
      r.feedback = response(rig.paths.feedback, 1.0, error);
      r.command = response(rig.paths.command, 0.0, error);
      for (double& u : r.command) u += rig.command_hold;
      return r;
    };
  }
};

TEST(LabIteration, TheTestPartIsWhereTheTargetLeavesItsLeadInAndLeadOut) {
  const auto target = lab_target();
  const TestWindow w = find_test_window(target, kDt);
  EXPECT_EQ(w.source, "lead-in/lead-out");
  EXPECT_NEAR(static_cast<double>(w.begin) * kDt, 5.0, 0.6);
  EXPECT_NEAR(static_cast<double>(w.end) * kDt, 20.0, 0.6);
  const auto weight = correction_weight(w, target, kDt, 1.0, 0.25);
  EXPECT_EQ(weight.front(), 0.0);
  EXPECT_EQ(weight[static_cast<std::size_t>(0.9 / kDt)], 0.0);  // the hold at home
  EXPECT_EQ(weight[static_cast<std::size_t>(4.5 / kDt)], 1.0);  // a second before the road
  EXPECT_EQ(weight.back(), 0.0);
  const auto set = window_from_times(6.0, 18.0, target.size(), kDt);
  EXPECT_EQ(set.begin, 2400u);
  EXPECT_EQ(set.end, 7200u);
  EXPECT_THROW(window_from_times(6.0, 40.0, target.size(), kDt), std::invalid_argument);
  EXPECT_EQ(parse_time_window("5:20.5"), (std::pair<double, double>{5.0, 20.5}));
  EXPECT_THROW(parse_time_window("5-20"), std::invalid_argument);
}

TEST(LabIteration, ARigWeakerAndLaterThanItsModelIsMetByTheAdaptedGain) {
  LinearRig lab(std::polar(0.75, -0.3));  // 25 % weaker, 17 degrees later in every band
  IterationSettings s;
  s.max_iterations = 6;
  s.tolerance_percent = 5.0;
  const auto target = lab_target();
  const IterationOutcome out = iterate_drive(target, lab.rig, s);
  std::string errors;
  for (const auto& i : out.iterations) {
    errors += " " + std::to_string(i.match.rel_rms_percent) + " (rod " + std::to_string(i.measured.rod_velocity / i.peaks.predicted.rod_velocity) +
              ", u " + std::to_string(i.measured.valve_effort / i.peaks.predicted.valve_effort) + ")";
  }
  ASSERT_EQ(out.end, IterationEnd::kTolerance) << out.end_detail << errors;
  ASSERT_GE(out.iterations.size(), 2u);
  const auto& first = out.iterations.front();
  EXPECT_DOUBLE_EQ(first.level, 0.5);
  // The drive starts and ends at home with the target: nothing below the stroke's bottom.
  EXPECT_EQ(first.drive.front(), target.front());
  EXPECT_EQ(first.drive.back(), target.back());
  EXPECT_GE(first.peaks.min, 0.0);
  for (std::size_t k = 1; k < out.iterations.size(); ++k) {
    EXPECT_LT(out.iterations[k].match.rel_rms_percent, out.iterations[k - 1].match.rel_rms_percent);
  }
  // The gain grew above the first 0.9 where the rig is weaker than the model.
  double largest = 0.0;
  for (double g : out.iterations[1].gain) largest = std::max(largest, g);
  EXPECT_GT(largest, 1.0);
  // From the third drive on (the second was the first at full level) the
  // prediction, corrected by the last measured ratio, holds to 5 %.
  ASSERT_GE(out.iterations.size(), 3u);
  for (std::size_t k = 2; k < out.iterations.size(); ++k) {
    const auto& i = out.iterations[k];
    EXPECT_NEAR(i.measured.rod_velocity / i.peaks.predicted.rod_velocity, 1.0, 0.05) << k;
    EXPECT_NEAR(i.measured.valve_effort / i.peaks.predicted.valve_effort, 1.0, 0.05) << k;
  }
  EXPECT_EQ(first.correction.velocity, 1.0);  // nothing measured before the first
  EXPECT_NE(out.iterations[1].correction.velocity, 1.0);
}

TEST(LabIteration, ADriveThatGrowsTooMuchIsRefusedWithTheReason) {
  LinearRig lab(std::polar(1.0, 0.0));
  IterationSettings s;
  s.max_growth = 1.5;  // the full drive after a half-level first pass grows about x2
  const IterationOutcome out = iterate_drive(lab_target(), lab.rig, s);
  EXPECT_EQ(out.end, IterationEnd::kDriveGrowth);
  EXPECT_EQ(lab.played, 1);
  EXPECT_NE(out.end_detail.find("drive 2 not played: its content in the band grew x"), std::string::npos) << out.end_detail;
  EXPECT_NE(out.end_detail.find("--max-growth"), std::string::npos) << out.end_detail;
}

TEST(LabIteration, ABandWhereTheRigAnswersAgainstTheModelIsGated) {
  // Band 0 (below the band) holds a ramp's energy; band 4 has too little to tell.
  const std::vector<double> current{0.9, 0.9, 0.9, 0.9, 0.9};
  const std::vector<double> energy{1e6, 1.0, 1.0, 1.0, 1e-4};
  const std::vector<std::complex<double>> ratio{{0.2, 0.0}, {1.0, 0.0}, std::polar(1.0, 1.2), {0.5, 0.0}, {0.5, 0.0}};
  const GainUpdate u = adapt_gain(ratio, energy, current);
  EXPECT_EQ(u.gain[0], 0.9);                    // below the band: kept
  EXPECT_NEAR(u.gain[1], 0.9, 1e-12);           // the model was right: 0.9 of the best gain 1
  EXPECT_EQ(u.gain[2], 0.0);                    // 69 degrees off: gated
  ASSERT_EQ(u.gated.size(), 1u);
  EXPECT_EQ(u.gated[0], 2u);
  EXPECT_NEAR(u.gain[3], 1.2, 1e-12);           // half as strong: 1.8 wanted, held at 1.2
  EXPECT_EQ(u.gain[4], 0.9);                    // not measured: kept
}

}  // namespace
}  // namespace rigctl
