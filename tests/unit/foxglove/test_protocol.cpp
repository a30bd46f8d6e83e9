// The Foxglove protocol's pieces without sockets: a client's bounded queue,
// the binary message frame, the subprotocols offered, what a client may ask,
// the sessions' handling of careless and hostile requests, the origin rule.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "foxglove/server/client_queue.hpp"
#include "foxglove/server/origin_policy.hpp"
#include "foxglove/server/protocol.hpp"
#include "foxglove/server/sessions.hpp"

using namespace rigctl::foxglove;

namespace {

std::shared_ptr<const std::string> text(const std::string& t) { return std::make_shared<const std::string>(t); }

TEST(ClientQueue, WhenFullDropsTheOldestDataAndCountsIt) {
  ClientQueue q(3, 1 << 20);
  for (uint64_t t = 1; t <= 5; ++t) q.push_data(7, t, text("m"));
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.dropped(), 2);
  QueuedMessage m;
  for (uint64_t want : {3u, 4u, 5u}) {
    ASSERT_TRUE(q.pop(m));
    EXPECT_EQ(m.log_time_ns, want);  // the newest kept, in order
  }
  EXPECT_FALSE(q.pop(m));
}

TEST(ClientQueue, AnswersAreNeverDroppedAndOverflowOnceOnlyAnswersAreLeft) {
  ClientQueue q(4, 1 << 20);
  q.push_data(7, 1, text("d1"));
  ASSERT_TRUE(q.push_text(text("a1")));
  q.push_data(7, 2, text("d2"));
  ASSERT_TRUE(q.push_text(text("a2")));
  ASSERT_TRUE(q.push_text(text("a3")));  // full: the oldest data made room
  ASSERT_TRUE(q.push_text(text("a4")));  // and the next
  EXPECT_EQ(q.dropped(), 2);
  EXPECT_FALSE(q.overflowed());
  EXPECT_FALSE(q.push_text(text("a5")));  // four answers unread: nothing left to drop
  EXPECT_TRUE(q.overflowed());
  QueuedMessage m;
  std::string order;
  while (q.pop(m)) order += *m.payload + " ";
  EXPECT_EQ(order, "a1 a2 a3 a4 ");
}

TEST(ClientQueue, BytesAreBoundedToo) {
  ClientQueue q(1000, 10);
  q.push_data(7, 1, text("123456"));
  q.push_data(7, 2, text("123456"));  // 12 bytes: the first goes
  EXPECT_EQ(q.size(), 1u);
  EXPECT_EQ(q.bytes(), 6u);
  EXPECT_FALSE(q.push_text(text("12345678901")));  // larger than the whole queue
  EXPECT_TRUE(q.overflowed());
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

TEST(Protocol, IdsOutsideTheUint32RangeAreRefusedNotTruncated) {
  for (const char* text : {R"({"op":"subscribe","subscriptions":[{"id":1099511627776,"channelId":1}]})",
                           R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})",
                           R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})",
                           R"({"op":"unsubscribe","subscriptionIds":[4294967296]})",
                           R"({"op":"unadvertise","channelIds":["7"]})"}) {
    const auto r = parse_client_request(text);
    EXPECT_EQ(r.kind, ClientRequest::Kind::kUnknown) << text;
    EXPECT_NE(r.error.find("0..4294967295"), std::string::npos) << r.error;
  }
  EXPECT_EQ(parse_client_request(R"({"op":"unsubscribe","subscriptionIds":[4294967295]})").unsubscriptions,
            std::vector<uint32_t>{4294967295u});
}

TEST(Protocol, EchoedTextIsClipped) {
  const std::string huge(100000, 'x');
  const auto r = parse_client_request("{\"op\":\"" + huge + "\"}");
  EXPECT_LE(r.op.size(), 64u + 3u);
  const auto bad = parse_client_request("[" + huge);
  EXPECT_LE(bad.error.size(), kMaxEchoedChars + 3u);
  EXPECT_EQ(clip("h\xc3\xa9llo", 2), "h...");  // not inside the two bytes of the e acute
}

// A client of the sessions: what it was sent, as JSON texts.
std::vector<nlohmann::json> sent_texts(Sessions& s, uint64_t id) {
  std::vector<nlohmann::json> out;
  QueuedMessage m;
  while (s.pop(id, m)) {
    if (!m.data && !m.binary) out.push_back(nlohmann::json::parse(*m.payload));
  }
  return out;
}

int count_status(const std::vector<nlohmann::json>& texts, const std::string& id) {
  int n = 0;
  for (const auto& t : texts) n += t.value("op", "") == "status" && t.value("id", "") == id ? 1 : 0;
  return n;
}

TEST(Sessions, DuplicateSubscriptionIdsAndChannelsAreRefusedAndCounted) {
  Sessions s{SessionsOptions{}};
  s.add_channel("A", "a", "{}");
  s.add_channel("B", "b", "{}");
  const uint64_t c = s.open("127.0.0.1:1", "foxglove.websocket.v1");
  s.handle_text(c, R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1},{"id":1,"channelId":2},{"id":2,"channelId":1},{"id":3,"channelId":9}]})");
  EXPECT_EQ(count_status(sent_texts(s, c), "bad_subscription"), 3);
  EXPECT_TRUE(s.has_subscribers(1));
  EXPECT_FALSE(s.has_subscribers(2));
  EXPECT_EQ(s.stats().refusals.at("bad_subscription"), 3);
}

TEST(Sessions, AClientThatDoesNotReadItsAnswersOverflowsAndIsNamedForClosing) {
  SessionsOptions o;
  o.queue_messages = 64;
  Sessions s{o};
  const uint64_t flooder = s.open("127.0.0.1:1", "foxglove.websocket.v1");
  const uint64_t reader = s.open("127.0.0.1:2", "foxglove.websocket.v1");
  for (int i = 0; i < 1000; ++i) s.handle_text(flooder, R"({"op":"getParameters","id":"x"})");
  const auto over = s.take_overflowed();
  ASSERT_EQ(over.size(), 1u);
  EXPECT_EQ(over[0].first, flooder);
  EXPECT_NE(over[0].second.find("did not read its answers"), std::string::npos) << over[0].second;
  EXPECT_TRUE(s.take_overflowed().empty());  // reported once
  EXPECT_FALSE(sent_texts(s, reader).empty());  // the other client has its greeting, nothing else changed
  s.close(flooder);
  EXPECT_EQ(s.open_count(), 1u);
  EXPECT_EQ(s.stats().clients, 2);
}

TEST(Sessions, ClosedClientsAreFreedAndOnlyTheLastOnesKeptForTheReport) {
  Sessions s{SessionsOptions{}};
  for (std::size_t i = 0; i < 3 * kClosedClientsKept; ++i) {
    const uint64_t id = s.open("127.0.0.1:" + std::to_string(i), "foxglove.sdk.v1");
    QueuedMessage m;
    ASSERT_TRUE(s.pop(id, m));  // its serverInfo went out
    s.close(id);
  }
  const ServerStats st = s.stats();
  EXPECT_EQ(st.clients, static_cast<int64_t>(3 * kClosedClientsKept));
  EXPECT_EQ(st.per_client.size(), kClosedClientsKept);
  EXPECT_EQ(st.per_client.back().address, "127.0.0.1:" + std::to_string(3 * kClosedClientsKept - 1));
  EXPECT_EQ(st.sent, static_cast<int64_t>(3 * kClosedClientsKept));  // every closed client's message still counts
}

TEST(OriginPolicy, OwnPagesAndAllowedOriginsOnly) {
  const OriginPolicy p("127.0.0.1", 8765, {"https://rig1.lab.example/"});
  EXPECT_EQ(p.check("127.0.0.1:8765", ""), "");                        // a desktop client: no Origin
  EXPECT_EQ(p.check("127.0.0.1:8765", "http://127.0.0.1:8765"), "");   // the server's own page
  EXPECT_EQ(p.check("localhost:8765", "http://localhost:8765"), "");
  EXPECT_EQ(p.check("127.0.0.1:8765", "https://rig1.lab.example"), "");  // the reverse proxy's page
  EXPECT_EQ(p.check("rig1.lab.example", "https://rig1.lab.example"), "");  // a proxy passing the browser's Host
  EXPECT_NE(p.check("127.0.0.1:8765", "http://evil.example"), "");       // another site's page
  EXPECT_NE(p.check("127.0.0.1:8765", "null"), "");
  EXPECT_NE(p.check("evil.example:8765", ""), "");                       // DNS rebinding: another name for 127.0.0.1
  EXPECT_NE(p.check("evil.example:8765", "http://evil.example:8765"), "");
  EXPECT_NE(p.check("", ""), "");
  EXPECT_NE(p.check("127.0.0.1:8766", ""), "");
  EXPECT_EQ(OriginPolicy::normalise_origin("HTTPS://Rig1.Lab.Example/"), "https://rig1.lab.example");
  EXPECT_EQ(OriginPolicy::normalise_origin("file:///x"), "");
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
