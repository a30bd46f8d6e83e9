// `rigctl iterate` on targets as a lab brings them (issue 29), every one
// written here, by this test's own writers (not the project's road-target
// or RPC III writer): a wheel-displacement target that starts at home,
// ramps to mid-stroke, carries 15 s of road (random content with a 1/f^2
// displacement spectrum over 0.7-12 Hz and two 8 mm half-cosine bumps of
// 0.25 s) and ramps home again. Played on the simulated quarter car with
// its bearing friction, in simulated time (--fast).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numbers>
#include <random>

#include "iteration_run.hpp"
#include "process.hpp"

namespace rigctl {
namespace {

const std::string kConfig = test::kQuarterCarConfig;

std::string fresh_dir(const std::string& name) { return test::fresh_dir("lab-targets", name); }
using test::rigctl;
using test::summary_of;

// ---- The target, as a function of time (so any sample rate can be written) ----

double half_cosine_ramp(double t, double t0, double length, double from, double to) {
  const double x = std::clamp((t - t0) / length, 0.0, 1.0);
  return from + (to - from) * (0.5 - 0.5 * std::cos(std::numbers::pi * x));
}

struct LabTarget {
  double home = 0.0, mid = 0.08;        // [m] setpoint_range's bottom, and mid-stroke
  double road_from = 5.0, road_to = 20.0;  // [s] the road part
  double duration = 23.0;
  double bump_height = 0.008, bump_length = 0.25;  // [m], [s]
  std::vector<double> bumps_at{9.0, 15.5};          // [s]
  std::vector<double> f, a, phase;  // random content: sines every 1/15 Hz over 0.7-12 Hz
  double scale = 1.0;               // on the random content

  explicit LabTarget(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 2 * std::numbers::pi);
    for (double fi = 0.7; fi <= 12.0; fi += 1.0 / 15.0) {
      f.push_back(fi);
      a.push_back(1.0 / fi);  // amplitude ~ 1/f: displacement PSD ~ 1/f^2
      phase.push_back(u(rng));
    }
  }

  double road(double t, double k) const {
    if (t <= road_from || t >= road_to) return 0.0;
    const double fade = std::min({1.0, t - road_from, road_to - t});  // 1 s in and out
    double x = 0.0;
    for (std::size_t i = 0; i < f.size(); ++i) x += a[i] * std::sin(2 * std::numbers::pi * f[i] * t + phase[i]);
    double bumps = 0.0;
    for (double b : bumps_at) {
      if (t >= b && t <= b + bump_length) bumps += bump_height * 0.5 * (1 - std::cos(2 * std::numbers::pi * (t - b) / bump_length));
    }
    return k * fade * fade * x + bumps;
  }

  double at(double t) const { return at_scale(t, scale); }

  // With the random content scaled by k.
  double at_scale(double t, double k) const {
    const double lead = t < 12.0 ? half_cosine_ramp(t, 1.0, 3.5, home, mid) : half_cosine_ramp(t, 20.5, 2.5, mid, home);
    return lead + road(t, k);
  }

  // The random content scaled (bisection) so the whole target's peak
  // velocity, sampled every millisecond, is v.
  void set_peak_velocity(double v) {
    const double dt = 1e-3;
    std::vector<double> rest, random;
    for (double t = 0.0; t < duration; t += dt) {
      const double bumps_and_lead = at_scale(t, 0.0);
      rest.push_back(bumps_and_lead);
      random.push_back(at_scale(t, 1.0) - bumps_and_lead);
    }
    const auto peak = [&](double k) {
      double p = 0.0;
      for (std::size_t i = 1; i < rest.size(); ++i) {
        p = std::max(p, std::abs(rest[i] - rest[i - 1] + k * (random[i] - random[i - 1])) / dt);
      }
      return p;
    };
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 50; ++i) (peak(0.5 * (lo + hi)) > v ? hi : lo) = 0.5 * (lo + hi);
    scale = 0.5 * (lo + hi);
  }
};

// ---- Independent writers ----

// A run file: t from t0 every dt, the channel and a text column to ignore.
void write_csv(const std::string& path, const LabTarget& target, double dt, double t0, const std::string& name) {
  std::ofstream f(path);
  f << "# written by the test, not by rigctl\nt," << name << ",note\n";
  f.precision(12);
  const auto n = static_cast<std::size_t>(std::llround(target.duration / dt));
  for (std::size_t i = 0; i < n; ++i) f << t0 + static_cast<double>(i) * dt << "," << target.at(static_cast<double>(i) * dt) << ",lab\n";
}

// RPC III from its description (a header of 512-byte blocks of four
// 128-byte records, keyword 32 bytes and value 96; data in groups of
// PTS_PER_GROUP points per channel, channel after channel; SHORT_INTEGER
// counts times SCALE.CHAN_n or FLOATING_POINT values). Written with 512
// points per frame and 4 frames per group, which the project's writer
// never uses.
struct RpcChannel {
  std::string name, unit;
  std::vector<double> values;
};

std::string scientific(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.9e", v);
  return b;
}

std::string rpc_record(const std::string& key, const std::string& value) {
  std::string r(128, '\0');
  std::memcpy(r.data(), key.data(), key.size());
  std::memcpy(r.data() + 32, value.data(), value.size());
  return r;
}

std::string rpc3_bytes(const std::vector<RpcChannel>& channels, double dt, bool integers,
                       const std::map<std::string, std::string>& overrides = {}) {
  const std::size_t per_frame = 512, per_group = 2048, n = channels.front().values.size();
  const std::size_t frames = (n + per_frame - 1) / per_frame;
  std::vector<std::pair<std::string, std::string>> rec{
      {"FILE_TYPE", "TIME_HISTORY"}, {"TIME_TYPE", "RESPONSE"}, {"DELTA_T", scientific(dt)},
      {"CHANNELS", std::to_string(channels.size())}, {"DATA_TYPE", integers ? "SHORT_INTEGER" : "FLOATING_POINT"},
      {"PTS_PER_FRAME", std::to_string(per_frame)}, {"PTS_PER_GROUP", std::to_string(per_group)},
      {"FRAMES", std::to_string(frames)}, {"PARTITIONS", "1"}};
  std::vector<double> scale;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    double peak = 0.0;
    for (double v : channels[c].values) peak = std::max(peak, std::abs(v));
    scale.push_back(peak / 32000.0);  // a full scale of its own, not the project's 32752
    const std::string k = std::to_string(c + 1);
    rec.push_back({"DESC.CHAN_" + k, channels[c].name});
    rec.push_back({"UNITS.CHAN_" + k, channels[c].unit});
    rec.push_back({"SCALE.CHAN_" + k, scientific(integers ? scale.back() : 1.0)});
  }
  for (const auto& [k, v] : overrides) {
    for (auto& r : rec) {
      if (r.first == k) r.second = v;
    }
  }
  const std::size_t params = rec.size() + 3, blocks = (params + 3) / 4;
  std::string out = rpc_record("FORMAT", "BINARY") + rpc_record("NUM_HEADER_BLOCKS", std::to_string(blocks)) +
                    rpc_record("NUM_PARAMS", std::to_string(params));
  for (const auto& [k, v] : rec) out += rpc_record(k, v);
  out.resize(blocks * 512, '\0');
  const std::size_t groups = (frames * per_frame + per_group - 1) / per_group;
  for (std::size_t g = 0; g < groups; ++g) {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      for (std::size_t i = 0; i < per_group; ++i) {
        const double x = channels[c].values[std::min(g * per_group + i, n - 1)];
        if (integers) {
          const auto q = static_cast<std::int16_t>(std::lround(x / scale[c]));
          out.append(reinterpret_cast<const char*>(&q), 2);
        } else {
          const auto q = static_cast<float>(x);
          out.append(reinterpret_cast<const char*>(&q), 4);
        }
      }
    }
  }
  return out;
}

std::vector<double> sampled(const std::function<double(double)>& x, double dt, double duration) {
  std::vector<double> v;
  for (std::size_t i = 0; i < static_cast<std::size_t>(std::llround(duration / dt)); ++i) v.push_back(x(static_cast<double>(i) * dt));
  return v;
}

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// ---- Checks ----

void expect_prediction_held(const nlohmann::json& s, double within) {
  for (const auto& i : s["iterations"]) {
    const auto& m = i["measured"];
    EXPECT_NEAR(m["rod_velocity_ratio"].get<double>(), 1.0, within) << "iteration " << i["iteration"] << ": " << i["predicted"];
    EXPECT_NEAR(m["valve_effort_ratio"].get<double>(), 1.0, within) << "iteration " << i["iteration"] << ": " << i["predicted"];
  }
}

void expect_each_better(const nlohmann::json& s, const std::string& output) {
  const auto& it = s["iterations"];
  for (std::size_t k = 1; k < it.size(); ++k) {
    EXPECT_LT(it[k]["rel_rms_percent"].get<double>(), it[k - 1]["rel_rms_percent"].get<double>())
        << "iteration " << k + 1 << " did not lower the error\n" << output;
  }
}

TEST(LabTargets, TheIssuesTargetReachesFivePercentOverItsRoadPartWithinSix) {
  const std::string dir = fresh_dir("road");
  LabTarget target(29);
  target.set_peak_velocity(0.15);
  write_csv(dir + "/target.csv", target, 0.0025, 0.0, "wheel");
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/target.csv --target-channel wheel --channel x_w --out " +
                        dir + "/out --fast --no-realtime");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  ASSERT_EQ(s["end"], "tolerance") << r.output;
  const auto& it = s["iterations"];
  ASSERT_LE(it.size(), 6u) << r.output;
  EXPECT_LE(it.back()["rel_rms_percent"].get<double>(), 5.0);
  expect_each_better(s, r.output);
  // The test part was found where the road leaves and rejoins the lead-in.
  EXPECT_EQ(s["window_source"], "lead-in/lead-out");
  EXPECT_NEAR(s["window_s"][0].get<double>(), target.road_from, 1.0) << s["window_s"];
  EXPECT_NEAR(s["window_s"][1].get<double>(), target.road_to, 1.0) << s["window_s"];
  // The first pass at half level; then full.
  EXPECT_DOUBLE_EQ(it[0]["level"].get<double>(), 0.5);
  // The drive starts and ends at home with the target, and never leaves the setpoint range.
  for (const auto& i : it) {
    EXPECT_GE(i["drive"]["min"].get<double>(), 0.0);
    EXPECT_LE(i["drive"]["max"].get<double>(), 0.16);
    EXPECT_GT(i["whole_rel_rms_percent"].get<double>(), 0.0);
  }
  expect_prediction_held(s, 0.2);
}

TEST(LabTargets, TwiceTheRodsTopSpeedIsRefusedNamingTheFlowBeforeAnythingPlays) {
  const std::string dir = fresh_dir("flow");
  LabTarget target(30);
  target.set_peak_velocity(0.6);  // the rod's top speed is about 0.29 m/s retracting, 0.37 extending
  write_csv(dir + "/target.csv", target, 0.0025, 0.0, "x_w");
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/target.csv --channel x_w --out " + dir +
                        "/out --fast --no-realtime");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["end"], "drive_limit");
  EXPECT_NE(s["end_detail"].get<std::string>().find("drive 1 not played: the target's drive at full level: flow: "),
            std::string::npos) << s["end_detail"];
  EXPECT_TRUE(s["iterations"].empty());
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/iter_01_run.csv"));  // nothing moved
}

TEST(LabTargets, BeyondTheStrokeIsRefusedNamingTheStrokeBeforeAnythingPlays) {
  const std::string dir = fresh_dir("stroke");
  LabTarget target(31);
  target.mid = 0.155;  // a road of centimetres about 155 mm: the rod would pass the 167 mm the stroke allows
  target.bump_height = 0.02;
  target.set_peak_velocity(0.15);
  write_csv(dir + "/target.csv", target, 0.0025, 0.0, "x_w");
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/target.csv --channel x_w --out " + dir +
                        "/out --fast --no-realtime");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["end"], "drive_limit");
  EXPECT_NE(s["end_detail"].get<std::string>().find("stroke: "), std::string::npos) << s["end_detail"];
  EXPECT_TRUE(s["iterations"].empty());
  EXPECT_FALSE(std::filesystem::exists(dir + "/out/iter_01_run.csv"));
}

// An RPC III file at 512 Hz with two channels, 16-bit counts with a scale
// per channel: the wheel is the second, chosen by number; resampled to the
// loop's 400 Hz.
TEST(LabTargets, RpcThreeMultiChannelAt512HzIsReadResampledAndIterated) {
  const std::string dir = fresh_dir("rpc512");
  LabTarget target(32);
  target.set_peak_velocity(0.12);
  const double dt = 1.0 / 512;
  const std::vector<RpcChannel> channels{
      {"spindle_acc", "m/s^2", sampled([&](double t) { return 9.81 * std::sin(3 * t); }, dt, target.duration)},
      {"wheel_z", "m", sampled([&](double t) { return target.at(t); }, dt, target.duration)}};
  write_file(dir + "/road.rsp", rpc3_bytes(channels, dt, true));
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/road.rsp --target-channel 2 --channel x_w --out " +
                        dir + "/out --fast --no-realtime --max-iterations 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["target_channel"], "wheel_z");
  EXPECT_NEAR(s["target_period_s"].get<double>(), dt, 1e-9);
  ASSERT_GE(s["iterations"].size(), 2u) << r.output;
  expect_each_better(s, r.output);
  EXPECT_LT(s["iterations"].back()["rel_rms_percent"].get<double>(), 10.0) << r.output;
  expect_prediction_held(s, 0.2);
}

// The same kind of file with 32-bit floating-point data, the channel chosen
// by its name: one half-level pass, its error that level's (about 50 %).
TEST(LabTargets, RpcThreeFloatingPointIsReadByChannelName) {
  const std::string dir = fresh_dir("rpcfloat");
  LabTarget target(35);
  target.set_peak_velocity(0.12);
  const double dt = 1.0 / 512;
  const std::vector<RpcChannel> channels{
      {"wheel_z", "m", sampled([&](double t) { return target.at(t); }, dt, target.duration)},
      {"body_z", "m", sampled([&](double t) { return 0.5 * target.at(t); }, dt, target.duration)}};
  write_file(dir + "/road.tim", rpc3_bytes(channels, dt, false));
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/road.tim --target-channel wheel_z --channel x_w --out " +
                        dir + "/out --fast --no-realtime --max-iterations 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["target_channel"], "wheel_z");
  EXPECT_NEAR(s["operating_point"].get<double>(), target.mid, 0.002);  // the wheel's, not the body's 40 mm
  ASSERT_EQ(s["iterations"].size(), 1u) << r.output;
  EXPECT_NEAR(s["iterations"][0]["rel_rms_percent"].get<double>(), 50.0, 10.0) << r.output;
  expect_prediction_held(s, 0.2);
}

// A run file sampled at 1 kHz whose time starts at 3 s: resampled, iterated,
// the error judged over the part --window sets (times from the record's start).
TEST(LabTargets, ARunFileAt1kHzStartingAt3sIsResampledAndIterated) {
  const std::string dir = fresh_dir("csv1k");
  LabTarget target(33);
  target.set_peak_velocity(0.12);
  write_csv(dir + "/target.csv", target, 0.001, 3.0, "x_w");
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/target.csv --channel x_w --out " + dir +
                        "/out --fast --no-realtime --max-iterations 2 --window 6:18");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary_of(dir + "/out");
  EXPECT_EQ(s["window_source"], "--window");
  EXPECT_NEAR(s["window_s"][0].get<double>(), 6.0, 1e-9);
  EXPECT_NEAR(s["window_s"][1].get<double>(), 18.0, 1e-9);
  EXPECT_NEAR(s["target_period_s"].get<double>(), 0.001, 1e-9);
  EXPECT_NEAR(s["target_start_s"].get<double>(), 3.0, 1e-9);
  ASSERT_EQ(s["iterations"].size(), 2u) << r.output;
  expect_each_better(s, r.output);
}

// Malformed RPC III files and a target too long: refused before anything
// is played, naming the keyword, the record or the limit.
TEST(LabTargets, MalformedOrTooLongTargetsAreRefusedNamingWhy) {
  const std::string dir = fresh_dir("malformed");
  LabTarget target(34);
  target.set_peak_velocity(0.1);
  const double dt = 1.0 / 512;
  const std::vector<RpcChannel> one{{"wheel_z", "m", sampled([&](double t) { return target.at(t); }, dt, target.duration)}};
  struct Case {
    std::string name, bytes, expect;
  };
  std::string no_format = rpc3_bytes(one, dt, true);
  std::memcpy(no_format.data(), "FORMAX", 6);
  std::string short_data = rpc3_bytes(one, dt, true);
  short_data.resize(short_data.size() - 4096);
  const std::vector<Case> cases{
      {"bad_delta.rsp", rpc3_bytes(one, dt, true, {{"DELTA_T", "fast"}}), "DELTA_T: 'fast' is not a number"},
      {"bad_type.rsp", rpc3_bytes(one, dt, true, {{"DATA_TYPE", "DOUBLE"}}), "DATA_TYPE DOUBLE"},
      {"no_format.rsp", no_format, "header record 1 is 'FORMAX', expected FORMAT"},
      {"short.rsp", short_data, "the data hold fewer than the header's"},
  };
  for (const auto& c : cases) {
    write_file(dir + "/" + c.name, c.bytes);
    const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/" + c.name + " --channel x_w --target-channel wheel_z --out " +
                          dir + "/out --fast --no-realtime");
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.name << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/out/iter_01_run.csv"));
  }
  write_csv(dir + "/long.csv", target, 0.0025, 0.0, "x_w");
  const auto bad_window = rigctl("iterate " + kConfig + " --target " + dir + "/long.csv --channel x_w --window 5-20 --out " +
                                 dir + "/out --fast --no-realtime");
  EXPECT_EQ(bad_window.exit_code, 1) << bad_window.output;
  EXPECT_NE(bad_window.output.find("--window '5-20': expected T0:T1 in seconds"), std::string::npos) << bad_window.output;
  const auto outside = rigctl("iterate " + kConfig + " --target " + dir + "/long.csv --channel x_w --window 5:40 --out " +
                              dir + "/out --fast --no-realtime");
  EXPECT_EQ(outside.exit_code, 1) << outside.output;
  EXPECT_NE(outside.output.find("needs 0 <= T0 < T1 <= 23"), std::string::npos) << outside.output;
  const auto r = rigctl("iterate " + kConfig + " --target " + dir + "/long.csv --channel x_w --max-length 20 --out " + dir +
                        "/out --fast --no-realtime");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("more than the 20.000000 s a drive may last (--max-length)"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace rigctl
