#include "foxglove/server/client.hpp"

#include <atomic>
#include <chrono>
#include <map>
#include <thread>

#include <nlohmann/json.hpp>
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

namespace rigctl::foxglove {

namespace {

using WsClient = websocketpp::client<websocketpp::config::asio_client>;
using Hdl = websocketpp::connection_hdl;
constexpr auto kRetryInterval = std::chrono::milliseconds(50);

template <typename T>
T read_le(const std::string& s, std::size_t at) {
  T v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<uint8_t>(s[at + i])) << (8 * i);
  return v;
}

}  // namespace

struct Client::Impl {
  std::string url, subprotocol;
  std::function<void(const ReceivedMessage&)> on_message;
  WsClient ws;
  std::thread thread;
  std::unique_ptr<asio::steady_timer> retry;
  std::atomic<bool> stopping{false}, open{false};
  std::atomic<int64_t> received{0};
  Hdl hdl;
  std::map<uint32_t, std::string> topic_of_subscription;
  uint32_t next_subscription = 1;

  void connect() {
    if (stopping.load()) return;
    websocketpp::lib::error_code ec;
    auto con = ws.get_connection(url, ec);
    if (ec) return;
    con->add_subprotocol(subprotocol, ec);
    hdl = con->get_handle();
    ws.connect(con);
  }

  void retry_later() {
    if (stopping.load()) return;
    retry->expires_after(kRetryInterval);
    retry->async_wait([this](const asio::error_code& ec) {
      if (!ec) connect();
    });
  }

  void on_text(const std::string& text) {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || j.value("op", "") != "advertise") return;
    nlohmann::json subs = nlohmann::json::array();
    for (const auto& c : j["channels"]) {
      const uint32_t id = next_subscription++;
      topic_of_subscription[id] = c["topic"].get<std::string>();
      subs.push_back({{"id", id}, {"channelId", c["id"]}});
    }
    websocketpp::lib::error_code ec;
    ws.send(hdl, nlohmann::json{{"op", "subscribe"}, {"subscriptions", subs}}.dump(), websocketpp::frame::opcode::text, ec);
  }

  void on_binary(const std::string& p) {
    if (p.size() < 13 || static_cast<uint8_t>(p[0]) != 0x01) return;
    const auto it = topic_of_subscription.find(read_le<uint32_t>(p, 1));
    if (it == topic_of_subscription.end()) return;
    received.fetch_add(1);
    on_message(ReceivedMessage{it->second, read_le<uint64_t>(p, 5), p.data() + 13, p.size() - 13});
  }
};

Client::Client(std::string url, std::string subprotocol, std::function<void(const ReceivedMessage&)> on_message)
    : impl_(std::make_unique<Impl>()) {
  Impl& c = *impl_;
  c.url = std::move(url);
  c.subprotocol = std::move(subprotocol);
  c.on_message = std::move(on_message);
  c.ws.clear_access_channels(websocketpp::log::alevel::all);
  c.ws.clear_error_channels(websocketpp::log::elevel::all);
  c.ws.init_asio();
  c.retry = std::make_unique<asio::steady_timer>(c.ws.get_io_service());
  c.ws.set_open_handler([&c](Hdl) { c.open.store(true); });
  c.ws.set_fail_handler([&c](Hdl) { c.retry_later(); });
  c.ws.set_close_handler([&c](Hdl) { c.open.store(false); });
  c.ws.set_message_handler([&c](Hdl, WsClient::message_ptr m) {
    if (m->get_opcode() == websocketpp::frame::opcode::text) {
      c.on_text(m->get_payload());
    } else {
      c.on_binary(m->get_payload());
    }
  });
}

Client::~Client() { stop(); }

void Client::start() {
  if (impl_->thread.joinable()) return;
  impl_->connect();
  impl_->thread = std::thread([this] { impl_->ws.run(); });
}

void Client::stop() {
  Impl& c = *impl_;
  if (c.stopping.exchange(true)) return;
  asio::post(c.ws.get_io_service(), [&c] {
    c.retry->cancel();
    websocketpp::lib::error_code ec;
    if (c.open.load()) c.ws.close(c.hdl, websocketpp::close::status::going_away, "done", ec);
  });
  if (c.thread.joinable()) c.thread.join();
}

bool Client::connected() const { return impl_->open.load(); }
int64_t Client::received() const { return impl_->received.load(); }

}  // namespace rigctl::foxglove
