// Procedure files (config/procedure_config.hpp, tools/procedure/procedure_loader.hpp):
// every step kind read, and errors that name the file, the line and the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "config/config_reader.hpp"
#include "config/procedure_config.hpp"
#include "config_edit.hpp"
#include "tools/procedure/procedure_loader.hpp"

using namespace rigctl;

namespace {

ChannelLayout quarter_car_layout() {
  ChannelLayout l;
  l.inputs = {{"x_r", "m"}, {"x_w", "m"}, {"x_b", "m"}, {"f_t", "N"}};
  l.outputs = {{"u", "1"}};
  return l;
}

const ChannelLayout kLayout = quarter_car_layout();
const ProcedureContext kContext{&kLayout, 0, 0.0025};

const std::string kEveryStep =
    "ramp_rate: 0.01\n"
    "rainflow: {channels: [x_r, f_t], basquin_exponent: 6, reference_range: 0.02}\n"
    "steps:\n"
    "  - ramp: {level: 0.08, rate: 0.02}\n"
    "  - hold: {time: 2.5}\n"
    "  - repeat:\n"
    "      count: 3\n"
    "      steps:\n"
    "        - sine: {mean: 0.08, amplitude: 0.005, frequency: 5, cycles: 1000, compensation: amplitude_phase,\n"
    "                 end_level: 0.08, peak_valley_detector: {channel: f_t, tolerance: 0.05, cycles: 3, action: hold}}\n"
    "        - blocks:\n"
    "            compensation: peak_valley\n"
    "            repeats: 10\n"
    "            rows:\n"
    "              - {mean: 0.08, amplitude: 0.002, frequency: 2, cycles: 20}\n"
    "              - {mean: 0.09, amplitude: 0.004, frequency: 1, cycles: 5}\n"
    "  - drive: {file: drive.csv, column: x_ref, repeats: 4}\n";

std::string error_of(const std::string& yaml) {
  try {
    procedure_from_string(yaml, "proc.yaml", kContext);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(ProcedureConfig, EveryStepKindIsRead) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "procedure-config";
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "proc.yaml") << kEveryStep;
    std::ofstream drive(dir / "drive.csv");
    drive << "t,x_ref\n";
    for (int i = 0; i <= 100; ++i) drive << i * 0.01 << "," << 0.08 + 0.001 * (i % 7) << "\n";  // 10 ms steps
  }
  const ProcedureSpec p = load_procedure_for_run((dir / "proc.yaml").string(), kContext);
  ASSERT_EQ(p.steps.size(), 7u);  // ramp, hold, repeat, sine, blocks, repeat end, drive
  EXPECT_EQ(p.steps[0].kind, StepKind::kRamp);
  EXPECT_DOUBLE_EQ(p.steps[0].level, 0.08);
  EXPECT_DOUBLE_EQ(p.steps[1].time_s, 2.5);
  EXPECT_EQ(p.steps[2].kind, StepKind::kRepeatBegin);
  EXPECT_EQ(p.steps[2].repeats, 3);
  EXPECT_EQ(p.steps[3].compensation.kind, Compensation::kAmplitudePhase);
  EXPECT_TRUE(p.steps[3].has_end_level);
  EXPECT_EQ(p.steps[3].peak_valley.channel, 3);
  EXPECT_EQ(p.steps[3].peak_valley.action, LimitAction::kHold);
  EXPECT_EQ(p.steps[4].rows.size(), 2u);
  EXPECT_EQ(p.steps[4].compensation.kind, Compensation::kPeakValley);
  EXPECT_EQ(p.steps[5].kind, StepKind::kRepeatEnd);
  EXPECT_EQ(p.steps[6].kind, StepKind::kDrive);
  EXPECT_EQ(p.steps[6].drive.size(), 401u);  // 1 s at 2.5 ms, both ends
  EXPECT_NEAR(p.steps[6].drive[4], 0.081, 1e-12);  // t = 10 ms: the file's second sample
  EXPECT_EQ(p.rainflow_channels, (std::vector<int>{0, 3}));
  // 3 x (1000 + 10 x 25) + 4 passes
  EXPECT_EQ(p.programmed_cycles(), 3 * (1000 + 250) + 4);
  EXPECT_EQ(p.hash.size(), 16u);
  EXPECT_NE(p.hash, procedure_from_string(kEveryStep + "  - hold: {time: 1}\n", "x", kContext).hash);
}

TEST(ProcedureConfig, ErrorsNameFileLineAndKey) {
  const std::string unknown_kind = "steps:\n  - ramp: {level: 0.1}\n  - sinus: {mean: 0}\n";
  EXPECT_NE(error_of(unknown_kind).find("proc.yaml:3: steps[1].sinus: unknown step 'sinus' (known: ramp, hold, sine, blocks, drive, repeat)"),
            std::string::npos)
      << error_of(unknown_kind);
  // A misspelt optional key is an unknown key at its own line; a missing
  // required one is named at its mapping.
  const std::string typo =
      "steps:\n  - sine:\n      mean: 0.08\n      amplitude: 0.01\n      frequency: 5\n      cycles: 10\n"
      "      compensaton: none\n";
  EXPECT_NE(error_of(typo).find("proc.yaml:" + std::to_string(test::line_of(typo, "compensaton")) +
                                ": steps[0].sine.compensaton: unknown key"),
            std::string::npos)
      << error_of(typo);
  const std::string missing = "steps:\n  - sine:\n      mean: 0.08\n      amplitud: 0.01\n";
  EXPECT_NE(error_of(missing).find("proc.yaml:3: steps[0].sine.amplitude: missing required key"), std::string::npos)
      << error_of(missing);
  const std::string bad_comp =
      "steps:\n  - sine: {mean: 0, amplitude: 0.01, frequency: 5, cycles: 10, compensation: amplitude}\n";
  EXPECT_NE(error_of(bad_comp).find("steps[0].sine.compensation: unknown compensation 'amplitude' (known: none, amplitude_phase, peak_valley)"),
            std::string::npos)
      << error_of(bad_comp);
  const std::string blocks_ap =
      "steps:\n  - blocks:\n      compensation: amplitude_phase\n      rows: [{mean: 0, amplitude: 0.01, frequency: 1, cycles: 2}]\n";
  EXPECT_NE(error_of(blocks_ap).find("proc.yaml:3: steps[0].blocks.compensation: a block program is compensated per level"),
            std::string::npos)
      << error_of(blocks_ap);
  const std::string channel =
      "steps:\n  - sine: {mean: 0, amplitude: 0.01, frequency: 5, cycles: 10,\n"
      "           peak_valley_detector: {channel: force, tolerance: 0.1, action: hold}}\n";
  EXPECT_NE(error_of(channel).find("steps[0].sine.peak_valley_detector.channel: unknown channel 'force' (inputs: x_r, x_w, x_b, f_t)"),
            std::string::npos)
      << error_of(channel);
  const std::string too_fast = "steps:\n  - sine: {mean: 0, amplitude: 0.01, frequency: 100, cycles: 10}\n";
  EXPECT_NE(error_of(too_fast).find("steps[0].sine.frequency"), std::string::npos) << error_of(too_fast);
  const std::string two_kinds = "steps:\n  - {ramp: {level: 0}, hold: {time: 1}}\n";
  EXPECT_NE(error_of(two_kinds).find("a step is one key naming its kind"), std::string::npos) << error_of(two_kinds);
  const std::string nested = "steps:\n  - repeat:\n      count: 2\n      steps:\n        - hold: {time: -1}\n";
  EXPECT_NE(error_of(nested).find("proc.yaml:5: steps[0].repeat.steps[0].hold.time"), std::string::npos)
      << error_of(nested);
}

TEST(ProcedureConfig, DriveFileErrorsNameTheStepAndFile) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "procedure-config-drive";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "proc.yaml") << "steps:\n  - drive: {file: missing.csv}\n";
  try {
    load_procedure_for_run((dir / "proc.yaml").string(), kContext);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("steps[0].drive: file '"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("missing.csv"), std::string::npos) << e.what();
  }
}

TEST(ProcedureConfig, CaptureIsReadAndItsErrorsNameTheKey) {
  const std::string ok =
      "capture: {channels: [f_t, x_r], histories: none, pre_trigger: 1.5, post_trigger: 2}\n"
      "steps:\n  - hold: {time: 1}\n";
  const ProcedureSpec spec = procedure_from_string(ok, "proc.yaml", kContext);
  EXPECT_TRUE(spec.capture.enabled);
  EXPECT_EQ(spec.capture.channels, (std::vector<int>{kLayout.input_index("f_t"), kLayout.input_index("x_r")}));
  EXPECT_FALSE(spec.capture.log_spaced_histories);
  EXPECT_EQ(spec.capture.pre_trigger_s, 1.5);
  EXPECT_EQ(spec.capture.post_trigger_s, 2.0);
  EXPECT_FALSE(procedure_from_string("steps:\n  - hold: {time: 1}\n", "proc.yaml", kContext).capture.enabled);
  const std::string bad_history = "capture: {histories: every}\nsteps:\n  - hold: {time: 1}\n";
  EXPECT_NE(error_of(bad_history).find("proc.yaml:1: capture.histories: log_spaced or none, not 'every'"), std::string::npos)
      << error_of(bad_history);
  const std::string bad_channel = "capture:\n  channels: [force]\nsteps:\n  - hold: {time: 1}\n";
  EXPECT_NE(error_of(bad_channel).find("capture.channels: unknown channel 'force'"), std::string::npos)
      << error_of(bad_channel);
  const std::string typo = "capture:\n  pre_triger: 1\nsteps:\n  - hold: {time: 1}\n";
  EXPECT_NE(error_of(typo).find("proc.yaml:2: capture.pre_triger: unknown key"), std::string::npos) << error_of(typo);
}
