// The console's exclusive control and its command gateway (foxglove/console):
// a take_control claim is checked like an operator command (tag, staleness,
// replay), one connection holds control at a time, and only its commands
// reach the command receiver's queue, the one the loop reads.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>

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

operator_command_t signed_claim(int64_t sequence, const OperatorKey& key, int64_t utime = kNow,
                                const std::string& sender = "alice@rigpc") {
  auto m = command(kTakeControlCommand, sequence, 0.0, utime, sender);
  sign(m, key);
  return m;
}

TEST(ConsoleControl, AClaimIsCheckedLikeACommand) {
  const auto key = key_of(7);
  ConsoleControl control(key, 2'000'000);
  EXPECT_EQ(control.claim(1, signed_claim(10, key_of(8)), kNow).reason, "bad_tag");
  EXPECT_EQ(control.claim(1, signed_claim(10, key, kNow - 3'000'000), kNow).reason, "stale");
  auto wrong_command = command("hold", 10);
  sign(wrong_command, key);
  EXPECT_EQ(control.claim(1, wrong_command, kNow).reason, "malformed");
  EXPECT_FALSE(control.holder().has_value());  // none of them took control

  EXPECT_TRUE(control.claim(1, signed_claim(10, key), kNow).ok());
  EXPECT_TRUE(control.holds(1));
  EXPECT_EQ(control.holder_sender(), "alice@rigpc");
  EXPECT_EQ(control.claim(1, signed_claim(10, key), kNow).reason, "replayed");  // the same claim again
}

TEST(ConsoleControl, OneConsoleHoldsControlUntilItReleasesIt) {
  const auto key = key_of(7);
  ConsoleControl control(key, 2'000'000);
  ASSERT_TRUE(control.claim(1, signed_claim(10, key), kNow).ok());
  const auto refused = control.claim(2, signed_claim(11, key, kNow, "bob"), kNow);
  EXPECT_EQ(refused.reason, kControlHeldReason);
  EXPECT_NE(refused.detail.find("alice@rigpc"), std::string::npos) << refused.detail;
  EXPECT_TRUE(control.holds(1));
  control.release(2);  // not the holder: nothing changes
  EXPECT_TRUE(control.holds(1));
  control.release(1);  // its console closed
  EXPECT_FALSE(control.holder().has_value());
  EXPECT_TRUE(control.claim(2, signed_claim(12, key, kNow, "bob"), kNow).ok());
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

class Gateway : public ::testing::Test {
 protected:
  void SetUp() override {
    key_path_ = std::filesystem::temp_directory_path() / ("rigctl_console_key_" + std::to_string(::getpid()));
    std::ofstream(key_path_) << std::string(32, '\x07');
    std::filesystem::permissions(key_path_, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write,
                                 std::filesystem::perm_options::replace);
    CommandReceiverOptions o;
    o.lcm_url = "memq://";
    o.key_path = key_path_.string();
    receiver_ = std::make_unique<CommandReceiver>(o);
    ServerOptions so;
    so.port = 0;
    server_ = std::make_unique<Server>(so);
    gateway_ = std::make_unique<ConsoleGateway>(*server_, *receiver_);
  }
  void TearDown() override { std::filesystem::remove(key_path_); }
  std::size_t queued() {
    std::size_t n = 0;
    OperatorCommand c;
    while (receiver_->queue().try_pop(c)) ++n;
    return n;
  }

  std::filesystem::path key_path_;
  std::unique_ptr<CommandReceiver> receiver_;
  std::unique_ptr<Server> server_;
  std::unique_ptr<ConsoleGateway> gateway_;
};

TEST_F(Gateway, OnlyTheConsoleInControlReachesTheLoopsQueue) {
  const auto key = key_of(7);
  const int64_t now = wall_utime();
  gateway_->on_client_message(1, kConsoleCommandTopic, json_command(command("hold", now, 0.0, now), key));
  EXPECT_EQ(queued(), 0u);  // nobody took control
  gateway_->on_client_message(1, kConsoleCommandTopic, json_command(command(kTakeControlCommand, now + 1, 0.0, now), key));
  gateway_->on_client_message(2, kConsoleCommandTopic, json_command(command("stop", now + 2, 0.0, now, "bob"), key));
  EXPECT_EQ(queued(), 0u);  // the other console watches
  gateway_->on_client_message(1, kConsoleCommandTopic, json_command(command("hold", now + 3, 0.0, now), key));
  EXPECT_EQ(queued(), 1u);
  // The holder's connection drops: control is free, and its commands are
  // no longer taken from that connection.
  gateway_->on_client_closed(1);
  gateway_->on_client_message(1, kConsoleCommandTopic, json_command(command("stop", now + 4, 0.0, now), key));
  EXPECT_EQ(queued(), 0u);
  gateway_->on_client_message(2, kConsoleCommandTopic, json_command(command(kTakeControlCommand, now + 5, 0.0, now, "bob"), key));
  gateway_->on_client_message(2, kConsoleCommandTopic, json_command(command("stop", now + 6, 0.0, now, "bob"), key));
  EXPECT_EQ(queued(), 1u);
  EXPECT_EQ(receiver_->counters().accepted(), 2u);  // the receiver's own counters: the same path as rigctl cmd
}

TEST_F(Gateway, UnreadableMessagesAreRefusedAndNothingIsQueued) {
  for (const char* payload : {"", "{not json", "[]", R"({"command":"hold"})", R"({"command":"hold","sender":"a","sequence":1,"utime":1,"tag":"zz"})",
                              R"({"command":7})"}) {
    gateway_->on_client_message(1, kConsoleCommandTopic, payload);
  }
  EXPECT_EQ(queued(), 0u);
  EXPECT_EQ(receiver_->counters().accepted() + receiver_->counters().rejected(), 0u);  // none got as far as the verifier
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
  const std::string page = http(server.port(), "GET /?x=1 HTTP/1.1\r\nHost: rig\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(page.rfind("HTTP/1.1 200", 0), 0u) << page.substr(0, 200);
  EXPECT_NE(page.find("Content-Security-Policy: default-src 'self'"), std::string::npos);
  EXPECT_NE(page.find("<title>rigctl console</title>"), std::string::npos);
  const std::string missing = http(server.port(), "GET /nope HTTP/1.1\r\nHost: rig\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(missing.rfind("HTTP/1.1 404", 0), 0u) << missing.substr(0, 200);
  const std::string post = http(server.port(), "POST / HTTP/1.1\r\nHost: rig\r\nContent-Length: 0\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(post.rfind("HTTP/1.1 405", 0), 0u) << post.substr(0, 200);
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
  EXPECT_EQ(j["states"]["off"].size(), 10u);
}

}  // namespace
