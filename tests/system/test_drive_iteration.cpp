// `rigctl iterate` on the simulated quarter car with its bearing friction
// and leakage (issue 19): a wheel-displacement target from an ISO 8608
// class C road reproduced within 5 % relative RMS over 0.5-30 Hz in at most
// 6 iterations, the error falling at every one, with the inverse from the
// nominal model and from an FRF measured by `rigctl identify`; targets
// beyond the actuator's reach end at the limit that stops them, without a
// trip. Every run is in simulated time (--fast).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "iteration_run.hpp"
#include "process.hpp"
#include "tools/iterate/rpc3_file.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

const std::string kConfig = test::kQuarterCarConfig;

std::string fresh_dir(const std::string& name) { return test::fresh_dir("drive-iteration", name); }
using test::rigctl;
using test::summary_of;

// Class C road at 2 m/s: the wheel's peak velocity (0.1 m/s) leaves the
// drive, which must lead the wheel through the loop, room inside the 20
// l/min valve (about 0.29 m/s at full opening when retracting).
std::string road_target(const std::string& dir) {
  const std::string path = dir + "/target.csv";
  const auto r = rigctl("road-target " + kConfig + " --class C --speed 2 --duration 20 --out " + path);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return path;
}

// A sine about mid-stroke as a target run file (t, x_w and a column to ignore).
std::string sine_target(const std::string& dir, double amplitude, double f_hz) {
  const std::string path = dir + "/sine.csv";
  std::ofstream f(path);
  f << "t,x_w,comment\n";
  for (int i = 0; i < 4000; ++i) {
    const double t = i * 0.0025;
    const double fade = std::min({1.0, t, 10.0 - t});  // 1 s ramps in and out
    f << t << "," << 0.08 + fade * amplitude * std::sin(2 * std::numbers::pi * f_hz * t) << ",x\n";
  }
  return path;
}

void expect_converged_within_six(const nlohmann::json& s, const std::string& output) {
  ASSERT_EQ(s["end"], "tolerance") << output;
  EXPECT_TRUE(s["converged"].get<bool>());
  const auto& it = s["iterations"];
  ASSERT_GE(it.size(), 1u);
  ASSERT_LE(it.size(), 6u) << output;
  EXPECT_LE(it.back()["rel_rms_percent"].get<double>(), 5.0);
  EXPECT_GT(it.back()["trac"].get<double>(), 0.99);
  for (std::size_t k = 1; k < it.size(); ++k) {
    EXPECT_LT(it[k]["rel_rms_percent"].get<double>(), it[k - 1]["rel_rms_percent"].get<double>())
        << "iteration " << k + 1 << " did not lower the error\n" << output;
  }
  for (const auto& i : it) {
    EXPECT_GT(i["peak_error"].get<double>(), 0.0);
    EXPECT_GT(i["drive"]["peak_velocity"].get<double>(), 0.0);
    EXPECT_GT(i["predicted"]["valve_effort"].get<double>(), 0.0);
    EXPECT_LE(i["predicted"]["valve_effort"].get<double>(), 0.8);
    EXPECT_LE(i["measured"]["valve_effort"].get<double>(), 0.8);
    // The rod's velocity is predicted to 20 %; the valve's effort too once
    // one drive was measured: the first, at half level, meets the worn
    // seal's leak that the nominal model lacks (it needed 1.5 times the
    // predicted command), and its ratio corrects the next prediction
    // (docs/drive-iteration.md 3).
    EXPECT_NEAR(i["measured"]["rod_velocity_ratio"].get<double>(), 1.0, 0.2) << i;
    if (i["iteration"] != 1) EXPECT_NEAR(i["measured"]["valve_effort_ratio"].get<double>(), 1.0, 0.2) << i;
    EXPECT_EQ(i["drive"]["scale"].get<double>(), 1.0);
  }
}

// Every iteration left its drive and response as run files the reader accepts.
void expect_iteration_files(const std::string& dir, const nlohmann::json& s) {
  for (const auto& i : s["iterations"]) {
    RunFileOptions drive_columns;
    drive_columns.required = {"x_ref"};
    const RunFile d = read_run_file(dir + "/" + i["drive_file"].get<std::string>(), drive_columns);
    RunFileOptions response_columns;
    response_columns.required = {"x_w", "target"};
    const RunFile r = read_run_file(dir + "/" + i["response_file"].get<std::string>(), response_columns);
    EXPECT_EQ(d.size(), 8000u);
    EXPECT_EQ(r.size(), 8000u);
    EXPECT_NEAR(d.dt, 0.0025, 1e-9);
  }
}

// The road target iterated on the rig with the given inverse (and rig
// options); the run must end by itself, exit 0.
nlohmann::json iterate_road(const std::string& dir, const std::string& options, std::string& output) {
  const auto r = rigctl("iterate " + kConfig + " --target " + road_target(dir) + " --channel x_w --out " + dir +
                        "/out --fast --no-realtime " + options);
  output = r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return summary_of(dir + "/out");
}

// The rig: the config's Karnopp bearing friction and laminar leakage, and a
// worn piston seal's turbulent cross-port leak the nominal model lacks.
const std::string kWornSeal = "--effect cross_port_leakage";

TEST(DriveIteration, NominalModelInverseReachesFivePercentWithinSixIterations) {
  const std::string dir = fresh_dir("nominal");
  std::string output;
  const auto s = iterate_road(dir, kWornSeal, output);
  EXPECT_EQ(s["frf_source"], "nominal model");
  EXPECT_EQ(s["channel"], "x_w");
  expect_converged_within_six(s, output);
  expect_iteration_files(dir + "/out", s);
}

TEST(DriveIteration, DiagnosisModelInverseReachesFivePercentWithinSixIterations) {
  const std::string dir = fresh_dir("diagnosis");
  // The diagnosis of this very rig (tests/data/README.md says how it was made).
  const std::string diagnosis = std::string(RIGCTL_TEST_DATA) + "/quarter_car_worn_seal_diagnosis.json";
  std::string output;
  const auto s = iterate_road(dir, kWornSeal + " --model " + diagnosis, output);
  EXPECT_EQ(s["frf_source"], "diagnosis model " + diagnosis);
  expect_converged_within_six(s, output);
}

TEST(DriveIteration, MeasuredFrfInverseReachesFivePercentWithinSixIterations) {
  const std::string dir = fresh_dir("measured");
  const auto id = rigctl("identify " + kConfig + " --out " + dir + "/frf.json --fast --no-realtime --response x_w --log " +
                         dir + "/identify.lcm");
  ASSERT_EQ(id.exit_code, 0) << id.output;
  std::string output;
  const auto s = iterate_road(dir, "--frf " + dir + "/frf.json", output);  // the rig identify measured
  EXPECT_EQ(s["frf_source"], "frf " + dir + "/frf.json");
  expect_converged_within_six(s, output);
}

TEST(DriveIteration, RpcThroughoutTargetInDrivesAndResponsesOut) {
  const std::string dir = fresh_dir("rpc");
  const auto made = rigctl("road-target " + kConfig + " --class C --speed 2 --duration 20 --out " + dir + "/road.rsp");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/road.rsp --channel x_w --out " + dir +
                        "/out --fast --no-realtime --max-iterations 2 --tolerance 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  ASSERT_EQ(s["iterations"].size(), 2u) << r.output;
  // The RPC III drive and response of each iteration hold what its run files hold.
  const Rpc3File drive = read_rpc3_file(dir + "/out/iter_02_drive.drv");
  const Rpc3File response = read_rpc3_file(dir + "/out/iter_02_response.rsp");
  EXPECT_EQ(drive.time_type, "DRIVE");
  EXPECT_EQ(response.time_type, "RESPONSE");
  EXPECT_NEAR(drive.period_s, 0.0025, 1e-12);
  RunFileOptions drive_columns;
  drive_columns.required = {"x_ref"};
  const RunFile csv_drive = read_run_file(dir + "/out/iter_02_drive.csv", drive_columns);
  RunFileOptions response_columns;
  response_columns.required = {"x_w", "target"};
  const RunFile csv_response = read_run_file(dir + "/out/iter_02_response.csv", response_columns);
  const auto& d = drive.channel("x_ref", "drv");
  const auto& y = response.channel("x_w", "rsp");
  const auto& target = response.channel("target", "rsp");
  ASSERT_GE(d.size(), csv_drive.size());
  for (std::size_t i = 0; i < csv_drive.size(); ++i) {
    ASSERT_NEAR(d[i], csv_drive.col("x_ref")[i], 0.1 / 32752 + 1e-9) << i;  // half a count of a 0.1 m peak at most
    ASSERT_NEAR(y[i], csv_response.col("x_w")[i], 0.1 / 32752 + 1e-9) << i;
    ASSERT_NEAR(target[i], csv_response.col("target")[i], 0.1 / 32752 + 1e-9) << i;
  }
}

TEST(DriveIteration, AnFrfWithoutTheChannelSaysHowToMeasureIt) {
  const std::string dir = fresh_dir("no-channel");
  const auto id = rigctl("identify " + kConfig + " --out " + dir + "/frf.json --fast --no-realtime --log " + dir + "/i.lcm");
  ASSERT_EQ(id.exit_code, 0) << id.output;
  const auto r = rigctl("iterate " + kConfig + " --target " + sine_target(dir, 0.005, 1.0) + " --channel x_w --frf " +
                        dir + "/frf.json --out " + dir + "/out --fast --no-realtime");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no closed-loop response of 'x_w' (the file has x_r; measure it with rigctl identify --response x_w)"),
            std::string::npos) << r.output;
}

TEST(DriveIteration, ATargetMissingTheChannelIsRefusedNamingIt) {
  const std::string dir = fresh_dir("bad-target");
  const auto r = rigctl("iterate " + kConfig + " --target " + sine_target(dir, 0.005, 1.0) + " --channel x_b --out " +
                        dir + "/out --fast --no-realtime");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("x_b"), std::string::npos) << r.output;
}

// A band from 0 Hz has no third-octave bands to step through (the update's
// bands would never end): refused before anything is played.
TEST(DriveIteration, ABandFromZeroOrAboveNyquistIsRefusedNamingTheOption) {
  const std::string dir = fresh_dir("bad-band");
  const std::string target = sine_target(dir, 0.005, 1.0);
  for (const std::string band : {"--band 0", "--band 5 --band-max 2", "--band-max 250"}) {
    const auto r = rigctl("iterate " + kConfig + " --target " + target + " --channel x_w --out " + dir + "/out " +
                          band + " --fast --no-realtime");
    EXPECT_EQ(r.exit_code, 1) << band << ": " << r.output;
    EXPECT_NE(r.output.find("--band: needs 0 < low < high"), std::string::npos) << band << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/summary.json")) << band;
  }
}

TEST(DriveIteration, BeyondTheStrokeEndsAtTheStrokeLimitWithoutPlaying) {
  const std::string dir = fresh_dir("stroke");
  // 100 mm about mid-stroke, slowly (63 mm/s): the setpoint range leaves 80 mm either way.
  const auto r = rigctl("iterate " + kConfig + " --target " + sine_target(dir, 0.1, 0.1) + " --channel x_w --out " +
                        dir + "/out --fast --no-realtime");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["end"], "drive_limit");
  EXPECT_NE(s["end_detail"].get<std::string>().find("drive 1 not played: the target's drive at full level: stroke: "),
            std::string::npos) << s["end_detail"];
  EXPECT_TRUE(s["iterations"].empty());
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/iter_01_run.csv"));  // nothing moved
}

TEST(DriveIteration, BeyondTheValvesFlowEndsAtTheFlowLimitWithoutATrip) {
  const std::string dir = fresh_dir("flow");
  // 12 mm at 6 Hz: 0.45 m/s, beyond what the valve can pass.
  const std::string target = sine_target(dir, 0.012, 6.0);
  const auto refused = rigctl("iterate " + kConfig + " --target " + target + " --channel x_w --out " + dir +
                              "/refused --fast --no-realtime");
  ASSERT_EQ(refused.exit_code, 0) << refused.output;
  const auto s = summary_of(dir + "/refused");
  EXPECT_EQ(s["end"], "drive_limit");
  EXPECT_NE(s["end_detail"].get<std::string>().find("drive 1 not played: the target's drive at full level: flow: "),
            std::string::npos) << s["end_detail"];
  EXPECT_FALSE(std::filesystem::exists(dir + "/refused/iter_01_run.csv"));  // nothing moved

  // Asked to scale, every drive is played scaled to the flow limit: each run
  // completes (a trip would end the iteration with run_ended and exit 3),
  // and the iteration ends naming the limit that holds it back.
  const auto scaled = rigctl("iterate " + kConfig + " --target " + target + " --channel x_w --out " + dir +
                             "/scaled --fast --no-realtime --scale --max-iterations 3");
  ASSERT_EQ(scaled.exit_code, 0) << scaled.output;
  const auto t = summary_of(dir + "/scaled");
  EXPECT_NE(t["end"], "run_ended");
  EXPECT_NE(t["end"], "tolerance");
  ASSERT_GE(t["iterations"].size(), 2u);
  for (const auto& i : t["iterations"]) {
    EXPECT_LE(i["predicted"]["valve_effort"].get<double>(), 0.8);
    if (i["iteration"] == 1) continue;  // the half-level first pass may fit as it is
    EXPECT_LT(i["drive"]["scale"].get<double>(), 1.0);
    EXPECT_EQ(i["drive"]["limited_by"].get<std::string>().rfind("flow: ", 0), 0u) << i["drive"]["limited_by"];
  }
  EXPECT_NE(t["end_detail"].get<std::string>().find("flow: "), std::string::npos) << t["end_detail"];
}

}  // namespace
}  // namespace rigctl
