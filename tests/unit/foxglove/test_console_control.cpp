// The console's exclusive control and its command gateway (foxglove/console):
// a take_control claim is verified by the command intake like an operator
// command (tag, staleness, replay, the same table), one connection holds
// control at a time, only its commands reach the loop's queue, but stop and
// hold come from every console; a silent or closed holder loses control.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>

#include <nlohmann/json.hpp>

#include "foxglove/console/console_assets.hpp"
#include "foxglove/console/console_control.hpp"
#include "foxglove/console/console_gateway.hpp"
#include "foxglove/console/station.hpp"
#include "operator_commands.hpp"

namespace {

using namespace rigctl;
using namespace rigctl::foxglove;
using rigctl::test::command;
using rigctl::test::key_of;
using rigctl::test::kNow;

TEST(ConsoleControl, OneConsoleHoldsControlUntilItReleasesIt) {
  ConsoleControl control;
  ASSERT_TRUE(control.claim(1, "alice@rigpc", kNow));
  EXPECT_FALSE(control.claim(2, "bob", kNow + 1));
  EXPECT_EQ(control.holder_sender(), "alice@rigpc");
  EXPECT_EQ(control.since_utime(), kNow);
  EXPECT_TRUE(control.claim(1, "alice@rigpc", kNow + 2));  // its holder again: still since the first claim
  EXPECT_EQ(control.since_utime(), kNow);
  EXPECT_FALSE(control.release(2));  // not the holder: nothing changes
  EXPECT_TRUE(control.holds(1));
  EXPECT_TRUE(control.release(1));  // its console closed
  EXPECT_FALSE(control.holder().has_value());
  EXPECT_TRUE(control.claim(2, "bob", kNow + 3));
  EXPECT_TRUE(control.holds(2));
}

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string json_command(const operator_command_t& m, const OperatorKey& key) {
  operator_command_t s = m;
  sign(s, key);
  return nlohmann::json{{"id", 1},          {"sender", s.sender},   {"sequence", s.sequence}, {"utime", s.utime},
                        {"command", s.command}, {"value", s.value}, {"tag", rigctl::test::hex(s.tag, 32)}}
      .dump();
}

// The gateway between the server's sessions and the command intake (the
// verifier, replay table and queue of the run's receiver), no sockets.
class Gateway : public ::testing::Test {
 protected:
  Gateway() {
    CommandIntakeOptions o;
    o.policy.not_before_utime = wall_utime() - 1'000'000;
    o.on_refusal = [this](const RejectionNote& n) { refusals_.push_back(n.reason); };
    intake_ = std::make_unique<CommandIntake>(key_of(7), o);
    ConsoleOptions co;
    co.control_timeout_s = 3.0;
    co.on_event = [this](const std::string&, const std::string& text) { events_.push_back(text); };
    gateway_ = std::make_unique<ConsoleGateway>(sessions_, *intake_, co);
    a_ = open();
    b_ = open();
  }
  uint64_t open() {
    const uint64_t id = sessions_.open("127.0.0.1:1", "foxglove.websocket.v1");
    sessions_.handle_text(id, R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":1}]})");  // the answers
    drain(id);
    return id;
  }
  // What the client was sent: its answers (JSON) and the ids of statuses.
  std::vector<nlohmann::json> drain(uint64_t id, std::vector<std::string>* statuses = nullptr) {
    std::vector<nlohmann::json> answers;
    QueuedMessage m;
    while (sessions_.pop(id, m)) {
      if (m.binary && !m.data) answers.push_back(nlohmann::json::parse(m.payload->substr(13)));
      if (!m.binary && statuses != nullptr) {
        const auto j = nlohmann::json::parse(*m.payload);
        if (j.value("op", "") == "status" || j.value("op", "") == "removeStatus") statuses->push_back(j.dump());
      }
    }
    return answers;
  }
  std::string send(uint64_t client, const std::string& name, int64_t sequence, const std::string& sender = "alice",
                   int64_t utime = 0) {
    const auto m = command(name, sequence, 0.0, utime == 0 ? wall_utime() : utime, sender);
    gateway_->on_client_message(client, kConsoleCommandTopic, json_command(m, key_of(7)));
    const auto answers = drain(client);
    return answers.empty() ? "no answer" : answers.back()["reason"].get<std::string>();
  }
  std::size_t queued() {
    std::size_t n = 0;
    OperatorCommand c;
    while (intake_->queue().try_pop(c)) ++n;
    return n;
  }

  Sessions sessions_{SessionsOptions{}};
  std::unique_ptr<CommandIntake> intake_;
  std::unique_ptr<ConsoleGateway> gateway_;
  std::vector<std::string> refusals_, events_;
  uint64_t a_ = 0, b_ = 0;
};

TEST_F(Gateway, StopAndHoldFromEveryConsoleOtherCommandsOnlyFromTheHolder) {
  EXPECT_EQ(send(a_, "start", 1), "not_in_control");  // nobody took control
  EXPECT_EQ(send(a_, "hold", 2), "accepted");           // no control needed
  EXPECT_EQ(queued(), 1u);
  EXPECT_EQ(send(a_, kTakeControlCommand, 3), "accepted");
  EXPECT_EQ(send(b_, "start", 4, "bob"), "not_in_control");
  EXPECT_EQ(send(b_, kTakeControlCommand, 5, "bob"), "control_held");
  EXPECT_EQ(send(b_, "stop", 6, "bob"), "accepted");  // the watching console stops the rig
  EXPECT_EQ(send(b_, "hold", 7, "bob"), "accepted");
  EXPECT_EQ(send(a_, "start", 8), "accepted");
  EXPECT_EQ(queued(), 3u);
  // Every refusal in the intake's counters and its log, as rigctl cmd's are.
  const RejectCounters& c = intake_->counters();
  EXPECT_EQ(c.get(RejectReason::kNotInControl), 2u);
  EXPECT_EQ(c.get(RejectReason::kControlHeld), 1u);
  EXPECT_EQ(c.accepted(), 4u);  // the queued commands; the claim queues nothing
  EXPECT_EQ(std::count(refusals_.begin(), refusals_.end(), "not_in_control"), 2);
  EXPECT_EQ(std::count(refusals_.begin(), refusals_.end(), "control_held"), 1);
}

TEST_F(Gateway, ClaimsAreVerifiedByTheIntakeAndForgeriesLearnNothingOfControl) {
  operator_command_t forged = command(kTakeControlCommand, 1, 0.0, wall_utime(), "mallory");
  gateway_->on_client_message(b_, kConsoleCommandTopic, json_command(forged, key_of(8)));
  EXPECT_EQ(drain(b_).back()["reason"], "bad_tag");
  EXPECT_EQ(send(a_, kTakeControlCommand, 10), "accepted");
  EXPECT_EQ(send(a_, kTakeControlCommand, 10), "replayed");
  EXPECT_EQ(send(a_, kTakeControlCommand, 11, "alice", wall_utime() - 30'000'000), "stale");
  // Signed before the intake started (a restart): refused, even within the window.
  EXPECT_EQ(send(b_, "stop", 12, "bob", wall_utime() - 1'500'000), "stale");
  operator_command_t forged_start = command("start", 2, 0.0, wall_utime(), "mallory");
  gateway_->on_client_message(b_, kConsoleCommandTopic, json_command(forged_start, key_of(8)));
  EXPECT_EQ(drain(b_).back()["reason"], "bad_tag");  // not not_in_control: the tag is checked first
  EXPECT_EQ(intake_->counters().get(RejectReason::kBadTag), 2u);
  EXPECT_EQ(intake_->counters().get(RejectReason::kStale), 2u);
  EXPECT_EQ(queued(), 0u);
}

TEST_F(Gateway, ASilentOrClosedHolderLosesControlWithAnEvent) {
  ASSERT_EQ(send(a_, kTakeControlCommand, 1), "accepted");
  gateway_->on_client_silent(a_, 1.0);  // one late pong: keeps it
  EXPECT_EQ(send(b_, kTakeControlCommand, 2, "bob"), "control_held");
  gateway_->on_client_silent(a_, 3.2);
  ASSERT_EQ(events_.size(), 2u);
  EXPECT_NE(events_[1].find("console control of 'alice' released: it answered no ping for 3.2 s"), std::string::npos) << events_[1];
  std::vector<std::string> statuses;
  drain(b_, &statuses);
  ASSERT_FALSE(statuses.empty());
  EXPECT_NE(statuses.back().find("removeStatus"), std::string::npos) << statuses.back();  // every console sees it is free
  EXPECT_EQ(send(b_, kTakeControlCommand, 3, "bob"), "accepted");
  EXPECT_EQ(send(a_, "start", 4), "not_in_control");  // alice's console came back: it watches
  sessions_.close(b_);
  EXPECT_NE(events_.back().find("console control of 'bob' released: its connection closed"), std::string::npos);
}

TEST_F(Gateway, ControlStatusSaysWhoAndSinceWhenAndReleaseIsAnsweredOnlyToItsSender) {
  ASSERT_EQ(send(a_, kTakeControlCommand, 1), "accepted");
  std::vector<std::string> statuses;
  drain(b_, &statuses);
  ASSERT_EQ(statuses.size(), 1u);
  EXPECT_NE(statuses[0].find("control held by alice since "), std::string::npos) << statuses[0];
  EXPECT_NE(statuses[0].find(" UTC"), std::string::npos) << statuses[0];
  // An unsigned release from a console without control changes nothing and
  // reaches no other console.
  for (int i = 0; i < 100; ++i) gateway_->on_client_message(b_, kConsoleCommandTopic, R"({"id":1,"command":"release_control"})");
  EXPECT_EQ(drain(b_).back()["reason"], "not_in_control");
  statuses.clear();
  drain(a_, &statuses);
  EXPECT_TRUE(statuses.empty());
  gateway_->on_client_message(a_, kConsoleCommandTopic, R"({"id":2,"command":"release_control"})");
  EXPECT_EQ(drain(a_, &statuses).back()["reason"], "accepted");
  EXPECT_EQ(statuses.size(), 1u);  // removeStatus
}

TEST_F(Gateway, UnreadableMessagesAreRefusedCountedAndNothingIsQueued) {
  const std::string huge(60000, 'x');
  for (const std::string payload : {std::string(""), std::string("{not json"), std::string("[]"), std::string(R"({"command":"hold"})"),
                                    std::string(R"({"command":"hold","sender":"a","sequence":1,"utime":1,"tag":"zz"})"),
                                    std::string(R"({"command":7})"),
                                    std::string(R"({"command":"hold","sender":"a","sequence":1e30,"utime":1,"tag":"00"})"),
                                    std::string(R"({"command":"hold","sender":"a","sequence":-1,"utime":"now","tag":"00"})"),
                                    R"({"command":")" + huge + R"(","sender":"a","sequence":1,"utime":1,"tag":"00"})",
                                    // Invalid UTF-8, quoted by the parse error: the answer must still be written
                                    // (found by fuzz_foxglove: the server's thread died on it).
                                    std::string("{\"op\":\xff\xff\xff\xff\x87")}) {
    gateway_->on_client_message(a_, kConsoleCommandTopic, payload);
    const auto answers = drain(a_);
    ASSERT_EQ(answers.size(), 1u) << payload.substr(0, 80);
    EXPECT_EQ(answers[0]["reason"], "malformed") << payload.substr(0, 80);
    EXPECT_LE(answers[0]["message"].get<std::string>().size(), 300u);  // echoed text clipped
    EXPECT_LE(answers[0]["command"].get<std::string>().size(), 40u);
  }
  EXPECT_EQ(queued(), 0u);
  EXPECT_EQ(intake_->counters().get(RejectReason::kMalformed), 10u);
}

TEST(ConsoleAssets, ThePageIsServedFromTheProgram) {
  const auto index = serve_console_asset("/");
  EXPECT_EQ(index.status, 200);
  EXPECT_EQ(index.content_type, "text/html; charset=utf-8");
  EXPECT_NE(index.body.find("<title>rigctl console</title>"), std::string::npos);
  for (const char* script : {"/foxglove.js", "/signing.js", "/scope.js", "/station.js", "/console.js"}) {
    EXPECT_NE(index.body.find(std::string("src=\"") + (script + 1) + "\""), std::string::npos) << script;
    const auto js = serve_console_asset(script);
    EXPECT_EQ(js.status, 200) << script;
    EXPECT_EQ(js.content_type, "text/javascript; charset=utf-8");
  }
  EXPECT_EQ(serve_console_asset("/console.css").content_type, "text/css; charset=utf-8");
  const auto missing = serve_console_asset("/../etc/passwd");
  EXPECT_EQ(missing.status, 404);
}

// One HTTP request to 127.0.0.1:port; the whole response (the server closes).
std::string http(uint16_t port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return "connect failed";
  }
  (void)!::write(fd, request.data(), request.size());
  std::string out;
  char buffer[4096];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) out.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  return out;
}

TEST(ConsoleAssets, TheServerAnswersPlainHttpOnItsWebSocketPort) {
  ServerOptions so;
  so.port = 0;
  Server server(so);
  server.set_http_handler(serve_console_asset);
  server.start();
  const std::string host = "Host: 127.0.0.1:" + std::to_string(server.port()) + "\r\n";
  const std::string page = http(server.port(), "GET /?x=1 HTTP/1.1\r\n" + host + "Connection: close\r\n\r\n");
  EXPECT_EQ(page.rfind("HTTP/1.1 200", 0), 0u) << page.substr(0, 200);
  EXPECT_NE(page.find("Content-Security-Policy: default-src 'self'"), std::string::npos);
  EXPECT_NE(page.find("<title>rigctl console</title>"), std::string::npos);
  EXPECT_NE(page.find("Server: rigctl\r\n"), std::string::npos) << page.substr(0, 400);  // no library, no version
  const std::string missing = http(server.port(), "GET /nope HTTP/1.1\r\n" + host + "Connection: close\r\n\r\n");
  EXPECT_EQ(missing.rfind("HTTP/1.1 404", 0), 0u) << missing.substr(0, 200);
  const std::string post = http(server.port(), "POST / HTTP/1.1\r\n" + host + "Content-Length: 0\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(post.rfind("HTTP/1.1 405", 0), 0u) << post.substr(0, 200);
  // A page asked for by another name (DNS rebinding) is refused.
  const std::string rebound = http(server.port(), "GET / HTTP/1.1\r\nHost: evil.example:" + std::to_string(server.port()) +
                                                      "\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(rebound.rfind("HTTP/1.1 403", 0), 0u) << rebound.substr(0, 200);
  server.stop();
}

TEST(Station, TheCommandTableIsTheStateMachines) {
  StationDescription s;
  s.rig = "quarter_car";
  s.detectors.push_back({"limits.x_r", "range", "x_r", "min -0.012, max 0.172", "interlock"});
  const auto j = nlohmann::json::parse(station_json(s));
  EXPECT_EQ(j["detectors"][0]["action"], "interlock");
  EXPECT_EQ(j["states"]["running"]["hold"]["allowed"], true);
  EXPECT_EQ(j["states"]["running"]["hold"]["to"], "holding");
  EXPECT_EQ(j["states"]["faulted"]["start"]["allowed"], false);
  EXPECT_FALSE(j["states"]["faulted"]["start"]["refused"].get<std::string>().empty());
  EXPECT_EQ(j["states"].size(), 8u);
  EXPECT_EQ(j["states"]["off"].size(), 11u);  // every operator command, stop_at_block_end included
}

}  // namespace
