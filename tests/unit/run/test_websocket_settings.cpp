// The Foxglove server's settings: `telemetry.websocket` in a config (strict,
// loopback unless an address is given), `--ws [ADDR:]PORT` over it, and the
// gains and limits it serves as read-only parameters.
#include <gtest/gtest.h>

#include <map>

#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "tools/run/rig_parameters.hpp"
#include "tools/run/ws_endpoint.hpp"

using namespace rigctl;

namespace {

std::string with_websocket(const std::string& section) {
  return test::edit(test::shipped_config(), "(  log_dir: runs[^\n]*\n)", "$1  websocket:" + section + "\n");
}

TEST(WebsocketSettings, AbsentFromTheShippedConfigsSoNoServerRuns) {
  EXPECT_FALSE(parse_rig_config(test::shipped_config(), "q.yaml").telemetry.websocket.has_value());
  EXPECT_FALSE(websocket_settings(std::nullopt, std::nullopt).has_value());
}

TEST(WebsocketSettings, ConfigGivesPortAndQueueAndBindsLoopbackUnlessToldOtherwise) {
  const auto ws = parse_rig_config(with_websocket(" {port: 9000, client_queue: 64}"), "q.yaml").telemetry.websocket;
  ASSERT_TRUE(ws.has_value());
  EXPECT_EQ(ws->address, "127.0.0.1");
  EXPECT_EQ(ws->port, 9000);
  EXPECT_EQ(ws->client_queue_messages, 64);
  EXPECT_EQ(parse_rig_config(with_websocket(" {address: 0.0.0.0, port: 0}"), "q.yaml").telemetry.websocket->address, "0.0.0.0");
}

TEST(WebsocketSettings, LimitsOriginsAndTimeoutsReachTheServer) {
  const auto defaults = parse_rig_config(with_websocket(" {port: 9000}"), "q.yaml").telemetry.websocket;
  const auto d = server_options(*defaults);
  EXPECT_EQ(d.max_clients, 16u);
  EXPECT_TRUE(d.allowed_origins.empty());
  EXPECT_EQ(d.client_timeout_s, 10.0);
  EXPECT_EQ(d.ping_interval_s, 1.0);  // control_timeout_s 3: a ping a second
  const auto ws = parse_rig_config(with_websocket(" {port: 9000, max_clients: 4, allowed_origins: [\"https://rig1.lab.example\"],"
                                                  " control_timeout_s: 0.6, client_timeout_s: 5}"),
                                   "q.yaml")
                      .telemetry.websocket;
  const auto o = server_options(*ws);
  EXPECT_EQ(o.max_clients, 4u);
  EXPECT_EQ(o.allowed_origins, std::vector<std::string>{"https://rig1.lab.example"});
  EXPECT_EQ(o.client_timeout_s, 5.0);
  EXPECT_DOUBLE_EQ(o.ping_interval_s, 0.2);  // a third of the control timeout
  EXPECT_EQ(ws->control_timeout_s, 0.6);
  test::expect_config_error(with_websocket(" {port: 1, allowed_origins: [\"rig1.lab.example\"]}"),
                            {"telemetry.websocket.allowed_origins[0]", "is not an origin"});
  test::expect_config_error(with_websocket(" {port: 1, allowed_origins: [\"https://rig1/path\"]}"), {"is not an origin"});
  test::expect_config_error(with_websocket(" {port: 1, max_clients: 0}"), {"telemetry.websocket.max_clients"});
  test::expect_config_error(with_websocket(" {port: 1, control_timeout_s: 0}"), {"telemetry.websocket.control_timeout_s"});
}

TEST(WebsocketSettings, BadValuesAreErrorsNamingTheKey) {
  test::expect_config_error(with_websocket(" {address: rigpc, port: 8765}"),
                            {"telemetry.websocket.address", "'rigpc' is not an IPv4 or IPv6 address"});
  test::expect_config_error(with_websocket(" {port: 70000}"), {"telemetry.websocket.port", "got 70000"});
  test::expect_config_error(with_websocket(" {port: 8765, publish: true}"), {"telemetry.websocket.publish", "unknown key"});
  test::expect_config_error(with_websocket(" {address: 127.0.0.1}"), {"telemetry.websocket.port", "missing required key"});
}

TEST(WebsocketSettings, OptionIsPortOrAddressAndPort) {
  EXPECT_EQ(parse_ws_endpoint("8765").port, 8765);
  EXPECT_FALSE(parse_ws_endpoint("8765").address.has_value());
  const auto any = parse_ws_endpoint("0.0.0.0:0");
  EXPECT_EQ(*any.address, "0.0.0.0");
  EXPECT_EQ(any.port, 0);
  EXPECT_EQ(*parse_ws_endpoint("[::1]:9000").address, "::1");
  for (const char* bad : {"", "http", "127.0.0.1:", "127.0.0.1:99999", "rigpc:8765", "8765x"}) {
    EXPECT_THROW(parse_ws_endpoint(bad), std::invalid_argument) << bad;
  }
  try {
    parse_ws_endpoint("rigpc:8765");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'rigpc' is not an IP address"), std::string::npos) << e.what();
  }
}

TEST(WebsocketSettings, OptionOverridesTheConfigKeepingItsAddressAndQueue) {
  WebsocketConfig config;
  config.address = "10.0.0.5";
  config.port = 9000;
  config.client_queue_messages = 64;
  const auto port_only = websocket_settings(config, parse_ws_endpoint("9100"));
  EXPECT_EQ(port_only->address, "10.0.0.5");
  EXPECT_EQ(port_only->port, 9100);
  EXPECT_EQ(port_only->client_queue_messages, 64);
  EXPECT_EQ(websocket_settings(config, parse_ws_endpoint("127.0.0.1:9100"))->address, "127.0.0.1");
  EXPECT_EQ(websocket_settings(std::nullopt, parse_ws_endpoint("9100"))->address, "127.0.0.1");
}

TEST(RigParameters, GainsAndLimitsOfTheConfigInSiUnits) {
  std::map<std::string, double> p;
  for (const auto& x : rig_parameters(parse_rig_config(test::shipped_config(), "q.yaml"))) p[x.name] = x.value;
  EXPECT_EQ(p.at("controller.kp"), 80.0);
  EXPECT_EQ(p.at("controller.ki"), 60.0);
  EXPECT_EQ(p.at("loop.period_s"), 0.0025);
  EXPECT_EQ(p.at("limits.p1.max"), 2.2e7);
  EXPECT_EQ(p.at("safety.detectors.x_r_rate.max"), 0.6);
  EXPECT_EQ(p.at("safety.detectors.x_r_rate.duration_s"), 0.01);
  // No limit is no parameter: the rate detector has no lower bound.
  EXPECT_EQ(p.count("safety.detectors.x_r_rate.min"), 0u);
  std::map<std::string, double> pneumatic;
  for (const auto& x : rig_parameters(parse_rig_config(test::shipped_config("pneumatic_rotary.yaml"), "p.yaml"))) {
    pneumatic[x.name] = x.value;
  }
  EXPECT_GT(pneumatic.count("controller.ke"), 0u);
}

}  // namespace
