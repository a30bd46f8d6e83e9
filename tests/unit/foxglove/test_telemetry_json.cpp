// Telemetry messages as JSON: the fields are the run-file columns in SI
// units, every message satisfies the schema made from its channel's first
// message, and a value that is not a number is null, not a made-up number.
#include <gtest/gtest.h>

#include <cmath>

#include <nlohmann/json.hpp>

#include "foxglove/telemetry/telemetry_json.hpp"

using namespace rigctl::foxglove;
using nlohmann::json;

namespace {

rigctl::sample_t sample() {
  rigctl::sample_t s{};
  s.utime = 1'700'000'000'000'000;
  s.tick = 12;
  s.t = 0.03;
  s.rig = "quarter_car";
  s.names = {"x_r", "p1"};
  s.units = {"m", "Pa"};
  s.values = {0.0125, NAN};
  s.num_channels = 2;
  s.status = 2;
  return s;
}

TEST(TelemetryJson, SampleFieldsAreTheRunFileColumns) {
  const json j = json::parse(to_json(sample()));
  EXPECT_EQ(j["t"], 0.03);
  EXPECT_EQ(j["tick"], 12);
  EXPECT_EQ(j["x_r"], 0.0125);
  EXPECT_TRUE(j["p1"].is_null());  // NaN: JSON has none
  EXPECT_EQ(log_time_ns(sample()), 1'700'000'000'000'000'000ull);
  const json schema = json::parse(json_schema(sample()));
  EXPECT_EQ(schema["title"], "rigctl.Sample");
  EXPECT_EQ(schema["properties"]["x_r"]["description"], "[m] input x_r");
  EXPECT_EQ(schema["properties"]["p1"]["description"], "[Pa] input p1");
  EXPECT_EQ(schema["required"], json::array({"t", "tick", "status", "x_r", "p1"}));
  EXPECT_FALSE(schema["additionalProperties"].get<bool>());
}

TEST(TelemetryJson, CommandNamesTheSetpointColumnAndTheOutputs) {
  rigctl::command_t c{};
  c.t = 0.03;
  c.setpoint_name = "x_ref";
  c.setpoint = 0.08;
  c.names = {"u"};
  c.units = {"1"};
  c.values = {0.25};
  const json j = json::parse(to_json(c));
  EXPECT_EQ(j["x_ref"], 0.08);
  EXPECT_EQ(j["u"], 0.25);
  EXPECT_EQ(json::parse(json_schema(c))["required"], json::array({"t", "tick", "x_ref", "u"}));
}

TEST(TelemetryJson, ChannelsNameEachFurtherChannelsDemandByItsColumnAndDecodeFromTheirTopic) {
  rigctl::channels_t c{};
  c.utime = 1'700'000'000'000'000;
  c.tick = 40;
  c.t = 0.1;
  c.num_channels = 2;
  c.setpoint_names = {"x_ref_2", "x_ref_3"};
  c.setpoints = {0.081, 0.079};
  c.measurements = {0.0805, 0.0792};
  c.outputs = {0.12, -1.0};
  c.saturated = {0, 1};
  std::vector<uint8_t> bytes(static_cast<std::size_t>(c.getEncodedSize()));
  ASSERT_GT(c.encode(bytes.data(), 0, static_cast<int>(bytes.size())), 0);
  const TelemetryTopics topics("RIG2_");
  ASSERT_EQ(topics.topic_of("RIG2_CHANNELS"), TelemetryTopic::kChannels);
  EXPECT_EQ(schema_name(TelemetryTopic::kChannels), "rigctl.Channels");
  const auto decoded = decode_telemetry(TelemetryTopic::kChannels, bytes.data(), bytes.size());
  ASSERT_TRUE(decoded.has_value());
  const json j = json::parse(to_json(*decoded));
  EXPECT_EQ(j["x_ref_2"], 0.081);
  EXPECT_EQ(j["measurement_2"], 0.0805);
  EXPECT_EQ(j["output_3"], -1.0);
  EXPECT_EQ(j["saturated_2"], false);
  EXPECT_EQ(j["saturated_3"], true);
  EXPECT_EQ(log_time_ns(*decoded), 1'700'000'000'000'000'000ull);
  const json schema = json::parse(json_schema(*decoded));
  EXPECT_EQ(schema["title"], "rigctl.Channels");
  EXPECT_EQ(schema["required"], json::array({"t", "tick", "x_ref_2", "measurement_2", "output_2", "saturated_2", "x_ref_3",
                                             "measurement_3", "output_3", "saturated_3"}));
}

TEST(TelemetryJson, ControllerFlagsAreBooleansAndTermsNamed) {
  rigctl::controller_t k{};
  k.controller = "pi";
  k.term_names = {"p", "i"};
  k.terms = {0.5, 0.1};
  k.saturated = 1;
  const json j = json::parse(to_json(k));
  EXPECT_EQ(j["term_p"], 0.5);
  EXPECT_EQ(j["term_i"], 0.1);
  EXPECT_TRUE(j["saturated"].is_boolean());
  EXPECT_TRUE(j["saturated"].get<bool>());
  EXPECT_EQ(json::parse(json_schema(k))["properties"]["saturated"]["type"], "boolean");
}

TEST(TelemetryJson, TimingDurationsAreSeconds) {
  rigctl::timing_t m{};
  m.tick = 400;
  m.period_ns = 2'500'000;
  m.latency_p99_ns = 50'000;
  m.stage_name = {"read"};
  m.stage_max_ns = {4'000};
  m.stage_mean_ns = {1'000.0};
  m.slowest_tick = 7;
  const json j = json::parse(to_json(m));
  EXPECT_DOUBLE_EQ(j["stage_read_max"].get<double>(), 4e-6);
  EXPECT_EQ(j["slowest_tick"], 7);
  EXPECT_DOUBLE_EQ(j["period"].get<double>(), 0.0025);
  EXPECT_DOUBLE_EQ(j["t"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(j["wakeup_latency_p99"].get<double>(), 50e-6);
  EXPECT_EQ(json::parse(json_schema(m))["properties"]["wakeup_latency_p99"]["description"], "[s] wake-up latency p99");
}

TEST(TelemetryJson, TopicsAreTheLcmChannelsOfThePrefix) {
  const TelemetryTopics topics("RIG2_");
  EXPECT_EQ(topics.topic_of("RIG2_SAMPLE"), TelemetryTopic::kSample);
  EXPECT_EQ(topics.topic_of("RIG2_DRIVER"), TelemetryTopic::kDriver);
  EXPECT_FALSE(topics.topic_of("RIGCTL_SAMPLE").has_value());
  EXPECT_FALSE(topics.topic_of("RIG2_OPERATOR").has_value());  // commands are not telemetry
  EXPECT_EQ(topics.channel_of(TelemetryTopic::kState), "RIG2_STATE");
  // Bytes that are not the channel's type are refused, not guessed at.
  const uint8_t junk[3] = {1, 2, 3};
  EXPECT_FALSE(decode_telemetry(TelemetryTopic::kSample, junk, sizeof junk).has_value());
}

}  // namespace
