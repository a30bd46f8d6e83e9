// The Foxglove protocol's pieces without sockets: a client's bounded queue,
// the binary message frame, the subprotocols offered, what a client may ask.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "foxglove/server/client_queue.hpp"
#include "foxglove/server/protocol.hpp"

using namespace rigctl::foxglove;

namespace {

QueuedMessage message(uint64_t t) { return QueuedMessage{7, t, std::make_shared<const std::string>("m")}; }

TEST(ClientQueue, WhenFullDropsTheOldestAndCountsIt) {
  ClientQueue q(3);
  for (uint64_t t = 1; t <= 5; ++t) q.push(message(t));
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.dropped(), 2);
  QueuedMessage m;
  for (uint64_t want : {3u, 4u, 5u}) {
    ASSERT_TRUE(q.pop(m));
    EXPECT_EQ(m.log_time_ns, want);  // the newest kept, in order
  }
  EXPECT_FALSE(q.pop(m));
}

TEST(Protocol, MessageDataFrameIsOpcodeSubscriptionTimeAndPayloadLittleEndian) {
  const std::string f = message_data_frame(0x01020304u, 0x1122334455667788ull, "{}");
  ASSERT_EQ(f.size(), 1u + 4u + 8u + 2u);
  EXPECT_EQ(static_cast<uint8_t>(f[0]), 0x01);
  EXPECT_EQ(static_cast<uint8_t>(f[1]), 0x04);
  EXPECT_EQ(static_cast<uint8_t>(f[4]), 0x01);
  EXPECT_EQ(static_cast<uint8_t>(f[5]), 0x88);
  EXPECT_EQ(static_cast<uint8_t>(f[12]), 0x11);
  EXPECT_EQ(f.substr(13), "{}");
}

TEST(Protocol, BothSubprotocolNamesAreSpokenAndNothingElse) {
  EXPECT_EQ(choose_subprotocol({"foxglove.websocket.v1"}), "foxglove.websocket.v1");
  EXPECT_EQ(choose_subprotocol({"foxglove.sdk.v1"}), "foxglove.sdk.v1");
  EXPECT_EQ(choose_subprotocol({"chat", "foxglove.sdk.v1", "foxglove.websocket.v1"}), "foxglove.sdk.v1");
  EXPECT_FALSE(choose_subprotocol({}).has_value());
  EXPECT_FALSE(choose_subprotocol({"foxglove.websocket.v2"}).has_value());
}

TEST(Protocol, ClientRequestsAreReadAndPublishingIsRefused) {
  const auto sub = parse_client_request(R"({"op":"subscribe","subscriptions":[{"id":4,"channelId":1},{"id":5,"channelId":2}]})");
  ASSERT_EQ(sub.kind, ClientRequest::Kind::kSubscribe);
  ASSERT_EQ(sub.subscriptions.size(), 2u);
  EXPECT_EQ(sub.subscriptions[1], std::make_pair(5u, 2u));
  EXPECT_EQ(parse_client_request(R"({"op":"unsubscribe","subscriptionIds":[4]})").unsubscriptions, std::vector<uint32_t>{4});
  const auto get = parse_client_request(R"({"op":"getParameters","parameterNames":["controller.kp"],"id":"r1"})");
  EXPECT_EQ(get.kind, ClientRequest::Kind::kGetParameters);
  EXPECT_EQ(get.request_id, "r1");
  EXPECT_EQ(get.parameter_names, std::vector<std::string>{"controller.kp"});
  const auto set = parse_client_request(R"({"op":"setParameters","parameters":[{"name":"controller.kp","value":1}],"id":"s"})");
  EXPECT_EQ(set.kind, ClientRequest::Kind::kSetParameters);
  EXPECT_EQ(set.parameter_names, std::vector<std::string>{"controller.kp"});
  const auto adv = parse_client_request(
      R"({"op":"advertise","channels":[{"id":7,"topic":"/rigctl/console/command","encoding":"json","schemaName":"c"}]})");
  ASSERT_EQ(adv.kind, ClientRequest::Kind::kAdvertise);
  ASSERT_EQ(adv.client_channels.size(), 1u);
  EXPECT_EQ(adv.client_channels[0].id, 7u);
  EXPECT_EQ(adv.client_channels[0].topic, "/rigctl/console/command");
  EXPECT_EQ(parse_client_request(R"({"op":"unadvertise","channelIds":[7]})").unadvertised, std::vector<uint32_t>{7});
  // A channel without its topic is unreadable, not a crash.
  EXPECT_EQ(parse_client_request(R"({"op":"advertise","channels":[{"id":7}]})").kind, ClientRequest::Kind::kUnknown);
  EXPECT_EQ(parse_client_request(R"({"op":"fetchAsset","uri":"x"})").kind, ClientRequest::Kind::kRefused);
  const auto garbage = parse_client_request("{not json");
  EXPECT_EQ(garbage.kind, ClientRequest::Kind::kUnknown);
  EXPECT_FALSE(garbage.error.empty());
}

TEST(Protocol, ClientMessageDataIsChannelThenPayload) {
  const std::string frame = std::string("\x01\x07\x00\x00\x00", 5) + R"({"a":1})";
  const auto m = parse_client_message_data(frame);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->channel, 7u);
  EXPECT_EQ(m->payload, R"({"a":1})");
  EXPECT_FALSE(parse_client_message_data(std::string("\x01\x07\x00", 3)).has_value());  // too short for the id
  EXPECT_FALSE(parse_client_message_data(std::string("\x02\x07\x00\x00\x00", 5)).has_value());  // another opcode
  const auto info = nlohmann::json::parse(server_info_json("rigctl", {}, "s1", /*client_publish=*/true));
  EXPECT_EQ(info["capabilities"], nlohmann::json::array({"parameters", "clientPublish"}));
  EXPECT_EQ(info["supportedEncodings"], nlohmann::json::array({"json"}));
}

TEST(Protocol, ServerMessagesCarryWhatClientsRead) {
  const auto info = nlohmann::json::parse(server_info_json("rigctl quarter_car", {{"rig", "quarter_car"}}, "s1"));
  EXPECT_EQ(info["op"], "serverInfo");
  EXPECT_EQ(info["capabilities"], nlohmann::json::array({"parameters"}));
  const auto adv = nlohmann::json::parse(advertise_json({{3, "RIGCTL_SAMPLE", "rigctl.Sample", "{}"}}));
  EXPECT_EQ(adv["channels"][0]["id"], 3);
  EXPECT_EQ(adv["channels"][0]["encoding"], "json");
  EXPECT_EQ(adv["channels"][0]["schemaEncoding"], "jsonschema");
  const auto status = nlohmann::json::parse(status_json("trip:limit_tripped:x_r", StatusLevel::kError, "x_r high"));
  EXPECT_EQ(status["level"], 2);
  EXPECT_EQ(status["id"], "trip:limit_tripped:x_r");
  EXPECT_EQ(nlohmann::json::parse(remove_status_json({"a"}))["statusIds"], nlohmann::json::array({"a"}));
  const auto values = nlohmann::json::parse(parameter_values_json({{"controller.kp", 80.0}}, "r1"));
  EXPECT_EQ(values["id"], "r1");
  EXPECT_EQ(values["parameters"][0]["value"], 80.0);
  EXPECT_FALSE(nlohmann::json::parse(parameter_values_json({}, "")).contains("id"));
}

}  // namespace
