// The Foxglove WebSocket server on websocketpp with standalone asio. Every
// socket operation runs on the server's one thread; other threads only queue
// (under the mutex) and post a flush.
#include "foxglove/server/server.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include "foxglove/server/client_queue.hpp"
#include "foxglove/server/protocol.hpp"

namespace rigctl::foxglove {

namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;

// Bytes a client's socket may have queued in websocketpp before the server
// stops handing it more: about a quarter second of every channel at 400 Hz.
// Past it the client is not keeping up and its messages wait in its own
// bounded queue, which drops the oldest.
constexpr std::size_t kMaxSocketBacklog = 256 * 1024;
// The kernel's share of a client's backlog (it doubles the value): with
// websocketpp's share above and the client's own queue, a client that stops
// reading holds about a second of data, and one 50 ms away still gets
// 2.5 MB/s, eight times what every channel at 400 Hz needs. Left to itself
// the kernel would grow it to megabytes: ten seconds of stale data.
constexpr int kSocketSendBuffer = 128 * 1024;
// A client that does not answer the close handshake is not waited for longer.
constexpr long kCloseTimeoutMs = 1000;
// How often the clients' queues go onto their sockets. Every 5 ms is two
// ticks of every channel per write at 400 Hz: a fraction of the wake-ups of
// the server, the clients and the kernel's loopback that a write per message
// would cost, on a machine whose other core runs the loop, for at most 5 ms
// of the 50 ms a client may lag. A client whose socket was full is tried
// again at the next flush.
constexpr auto kFlushInterval = std::chrono::milliseconds(5);

struct Client {
  Client(uint64_t i, Hdl h, std::size_t capacity) : id(i), hdl(std::move(h)), queue(capacity) {}
  uint64_t id;
  Hdl hdl;
  std::map<uint32_t, uint32_t> subscription_of_channel;
  std::map<uint32_t, ClientChannel> advertised;  // the client's own channels (clientPublish)
  ClientQueue queue;
  ClientStats stats;
};

}  // namespace

struct Server::Impl {
  ServerOptions options;
  WsServer ws;
  std::thread thread;
  uint16_t port = 0;
  std::string session_id;
  std::unique_ptr<asio::steady_timer> flush_timer;
  HttpHandler http;                                  // set before start()
  ClientPublishHandler* publish_handler = nullptr;   // likewise
  std::vector<std::string> publish_topics;

  mutable std::mutex mu;  // everything below
  std::map<Hdl, std::shared_ptr<Client>, std::owner_less<Hdl>> clients;
  std::vector<std::shared_ptr<Client>> seen;  // for the statistics, closed ones too
  std::vector<AdvertisedChannel> channels;
  std::map<std::string, std::pair<StatusLevel, std::string>> statuses;
  std::vector<Parameter> parameters;
  uint64_t next_client_id = 1;
  bool stopped = false;
  std::atomic<bool> stopping{false};  // the flush timer must not re-arm once set

  explicit Impl(ServerOptions o) : options(std::move(o)) {}

  std::shared_ptr<Client> client(const Hdl& hdl) {
    std::lock_guard<std::mutex> lock(mu);
    const auto it = clients.find(hdl);
    return it == clients.end() ? nullptr : it->second;
  }

  void send_text(const Hdl& hdl, const std::string& text) {
    websocketpp::lib::error_code ec;
    ws.send(hdl, text, websocketpp::frame::opcode::text, ec);  // a closing connection: nothing to do
  }

  void send_to_all(const std::string& text) {
    std::vector<Hdl> hdls;
    {
      std::lock_guard<std::mutex> lock(mu);
      for (const auto& [hdl, c] : clients) hdls.push_back(hdl);
    }
    for (const auto& hdl : hdls) send_text(hdl, text);
  }

  void post_to_all(std::string text) {
    asio::post(ws.get_io_service(), [this, text = std::move(text)] { send_to_all(text); });
  }

  bool validate(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    const auto chosen = choose_subprotocol(con->get_requested_subprotocols());
    if (!chosen) {
      con->set_status(websocketpp::http::status_code::bad_request);
      con->set_body("rigctl speaks the Foxglove WebSocket protocol: ask for subprotocol foxglove.websocket.v1 or foxglove.sdk.v1\n");
      return false;
    }
    con->select_subprotocol(*chosen);
    return true;
  }

  void on_open(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    std::vector<std::string> greeting{
        server_info_json(options.name, options.metadata, session_id, publish_handler != nullptr)};
    {
      std::lock_guard<std::mutex> lock(mu);
      auto c = std::make_shared<Client>(next_client_id++, hdl, options.client_queue_messages);
      c->stats.address = con->get_remote_endpoint();
      c->stats.subprotocol = con->get_subprotocol();
      clients.emplace(hdl, c);
      seen.push_back(c);
      greeting.push_back(advertise_json(channels));
      for (const auto& [id, status] : statuses) greeting.push_back(status_json(id, status.first, status.second));
    }
    for (const auto& text : greeting) send_text(hdl, text);
  }

  void on_close(const Hdl& hdl) {
    std::shared_ptr<Client> gone;
    {
      std::lock_guard<std::mutex> lock(mu);
      const auto it = clients.find(hdl);
      if (it == clients.end()) return;  // a handshake that failed: never opened
      gone = it->second;
      clients.erase(it);
    }
    if (publish_handler != nullptr) publish_handler->on_client_closed(gone->id);
  }

  // A binary frame: a message on a channel the client advertised, handed to
  // the publish handler; anything else is answered with a warning.
  void on_client_data(const Hdl& hdl, const Client& c, const std::string& frame) {
    const auto data = parse_client_message_data(frame);
    if (!data) {
      send_text(hdl, status_json("bad_client_message", StatusLevel::kWarning,
                                 "unreadable binary message: only opcode 1 (client message data) is accepted"));
      return;
    }
    std::string topic;
    {
      std::lock_guard<std::mutex> lock(mu);
      const auto it = c.advertised.find(data->channel);
      if (it != c.advertised.end()) topic = it->second.topic;
    }
    if (topic.empty() || publish_handler == nullptr) {
      send_text(hdl, status_json("bad_client_message", StatusLevel::kWarning,
                                 "client channel " + std::to_string(data->channel) + " was not advertised"));
      return;
    }
    publish_handler->on_client_message(c.id, topic, data->payload);
  }

  // Client channels: JSON on one of the accepted topics, or refused.
  void on_advertise(const Hdl& hdl, Client& c, const ClientRequest& r) {
    for (const auto& ch : r.client_channels) {
      const bool topic_ok = std::find(publish_topics.begin(), publish_topics.end(), ch.topic) != publish_topics.end();
      if (publish_handler == nullptr || !topic_ok || ch.encoding != "json") {
        send_text(hdl, status_json("refused_advertise", StatusLevel::kWarning,
                                   publish_handler == nullptr
                                       ? "rigctl serves read-only telemetry here: client publishing is not offered"
                                       : "client channel '" + ch.topic + "' (" + ch.encoding +
                                             ") refused: only JSON on the console's command topic"));
        continue;
      }
      std::lock_guard<std::mutex> lock(mu);
      c.advertised[ch.id] = ch;
    }
  }

  void on_message(const Hdl& hdl, WsServer::message_ptr msg) {
    auto c = client(hdl);
    if (!c) return;
    if (msg->get_opcode() != websocketpp::frame::opcode::text) {
      on_client_data(hdl, *c, msg->get_payload());
      return;
    }
    const ClientRequest r = parse_client_request(msg->get_payload());
    switch (r.kind) {
      case ClientRequest::Kind::kSubscribe: {
        std::lock_guard<std::mutex> lock(mu);
        for (const auto& [sub, channel] : r.subscriptions) {
          if (channel < channels.size() + 1 && channel > 0) c->subscription_of_channel[channel] = sub;
        }
        return;
      }
      case ClientRequest::Kind::kUnsubscribe: {
        std::lock_guard<std::mutex> lock(mu);
        for (const auto sub : r.unsubscriptions) {
          for (auto it = c->subscription_of_channel.begin(); it != c->subscription_of_channel.end();) {
            it = it->second == sub ? c->subscription_of_channel.erase(it) : std::next(it);
          }
        }
        return;
      }
      case ClientRequest::Kind::kAdvertise:
        on_advertise(hdl, *c, r);
        return;
      case ClientRequest::Kind::kUnadvertise: {
        std::lock_guard<std::mutex> lock(mu);
        for (const auto id : r.unadvertised) c->advertised.erase(id);
        return;
      }
      case ClientRequest::Kind::kGetParameters:
      case ClientRequest::Kind::kSetParameters:
        answer_parameters(hdl, r);
        return;
      case ClientRequest::Kind::kRefused:
        send_text(hdl, status_json("refused_" + r.op, StatusLevel::kWarning,
                                   "rigctl serves read-only telemetry: '" + r.op + "' is not offered"));
        return;
      case ClientRequest::Kind::kUnknown:
        send_text(hdl, status_json("bad_request", StatusLevel::kWarning,
                                   r.error.empty() ? "unknown op '" + r.op + "'" : "unreadable request: " + r.error));
        return;
    }
  }

  void answer_parameters(const Hdl& hdl, const ClientRequest& r) {
    std::vector<Parameter> answer;
    {
      std::lock_guard<std::mutex> lock(mu);
      for (const auto& p : parameters) {
        const bool wanted = r.parameter_names.empty() ||
                            std::find(r.parameter_names.begin(), r.parameter_names.end(), p.name) != r.parameter_names.end();
        if (wanted) answer.push_back(p);
      }
    }
    if (r.kind == ClientRequest::Kind::kSetParameters) {
      send_text(hdl, status_json("parameters_read_only", StatusLevel::kWarning,
                                 "the rig's gains and limits are read-only here: change the rig's config file"));
    }
    send_text(hdl, parameter_values_json(answer, r.request_id));
  }

  // On the server's thread: each client's queue onto its socket while the
  // socket keeps up.
  void flush() {
    std::vector<std::shared_ptr<Client>> open;
    {
      std::lock_guard<std::mutex> lock(mu);
      for (const auto& [hdl, c] : clients) open.push_back(c);
    }
    for (const auto& c : open) {
      websocketpp::lib::error_code ec;
      auto con = ws.get_con_from_hdl(c->hdl, ec);
      if (ec || con->get_state() != websocketpp::session::state::open) continue;
      QueuedMessage m;
      while (con->get_buffered_amount() < kMaxSocketBacklog) {
        {
          std::lock_guard<std::mutex> lock(mu);
          if (!c->queue.pop(m)) break;
        }
        con->send(message_data_frame(m.subscription, m.log_time_ns, *m.payload), websocketpp::frame::opcode::binary);
        std::lock_guard<std::mutex> lock(mu);
        ++c->stats.sent;
      }
    }
  }

  void on_http(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    if (!http) {
      con->set_status(websocketpp::http::status_code::upgrade_required);
      con->set_body("rigctl speaks the Foxglove WebSocket protocol here\n");
      return;
    }
    if (con->get_request().get_method() != "GET") {
      con->set_status(websocketpp::http::status_code::method_not_allowed);
      con->append_header("Allow", "GET");
      return;
    }
    std::string path = con->get_resource();
    path = path.substr(0, path.find('?'));
    const HttpResponse r = http(path);
    con->set_status(static_cast<websocketpp::http::status_code::value>(r.status));
    con->append_header("Content-Type", r.content_type);
    // The page and its scripts come from this server only, and nothing may
    // frame it (a control page inside another site's frame is clickjacking).
    con->append_header("Content-Security-Policy",
                       "default-src 'self'; connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'");
    con->append_header("X-Content-Type-Options", "nosniff");
    con->append_header("Cache-Control", "no-store");
    con->set_body(r.body);
  }

  void arm_flush_timer() {
    flush_timer->expires_after(kFlushInterval);
    flush_timer->async_wait([this](const asio::error_code& ec) {
      // Cancelled, or it fired just as stop() cancelled it: not again, or
      // the server's thread would never run out of work.
      if (ec || stopping.load()) return;
      flush();
      arm_flush_timer();
    });
  }
};

Server::Server(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  Impl& s = *impl_;
  s.session_id = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
  s.ws.clear_access_channels(websocketpp::log::alevel::all);
  s.ws.clear_error_channels(websocketpp::log::elevel::all);
  s.ws.init_asio();
  s.ws.set_reuse_addr(true);
  s.ws.set_close_handshake_timeout(kCloseTimeoutMs);
  // After the accept (before it the socket is not open yet).
  s.ws.set_tcp_post_init_handler([&s](Hdl hdl) {
    asio::error_code ec;
    auto& socket = s.ws.get_con_from_hdl(hdl)->get_raw_socket();
    // Small messages at 400 Hz: send each at once rather than wait for Nagle.
    socket.set_option(asio::ip::tcp::no_delay(true), ec);
    socket.set_option(asio::socket_base::send_buffer_size(kSocketSendBuffer), ec);
  });
  s.ws.set_validate_handler([&s](Hdl hdl) { return s.validate(hdl); });
  s.ws.set_open_handler([&s](Hdl hdl) { s.on_open(hdl); });
  s.ws.set_close_handler([&s](Hdl hdl) { s.on_close(hdl); });
  s.ws.set_fail_handler([&s](Hdl hdl) { s.on_close(hdl); });
  s.ws.set_message_handler([&s](Hdl hdl, WsServer::message_ptr m) { s.on_message(hdl, std::move(m)); });
  s.ws.set_http_handler([&s](Hdl hdl) { s.on_http(hdl); });
  const std::string where = s.options.address + ":" + std::to_string(s.options.port);
  try {
    asio::error_code ec;
    const auto address = asio::ip::make_address(s.options.address, ec);
    if (ec) throw std::runtime_error("'" + s.options.address + "' is not an IP address");
    s.ws.listen(asio::ip::tcp::endpoint(address, s.options.port));
    s.ws.start_accept();
    const auto local = s.ws.get_local_endpoint(ec);
    if (ec) throw std::runtime_error(ec.message());
    s.port = local.port();
  } catch (const websocketpp::exception& e) {
    throw std::runtime_error("foxglove server: cannot listen on " + where + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("foxglove server: cannot listen on " + where + ": " + e.what());
  }
  s.flush_timer = std::make_unique<asio::steady_timer>(s.ws.get_io_service());
}

Server::~Server() { stop(); }

void Server::start() {
  if (impl_->thread.joinable()) return;
  impl_->arm_flush_timer();
  impl_->thread = std::thread([this] { impl_->ws.run(); });
}

void Server::stop() {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.mu);
    if (s.stopped) return;
    s.stopped = true;
  }
  s.stopping.store(true);
  // On the server's thread: stop accepting, close every client, cancel the
  // timer; run() returns once nothing is left to do.
  asio::post(s.ws.get_io_service(), [&s] {
    websocketpp::lib::error_code ec;
    s.ws.stop_listening(ec);
    s.flush_timer->cancel();
    std::vector<Hdl> hdls;
    {
      std::lock_guard<std::mutex> lock(s.mu);
      for (const auto& [hdl, c] : s.clients) hdls.push_back(hdl);
    }
    for (const auto& hdl : hdls) s.ws.close(hdl, websocketpp::close::status::going_away, "rigctl stops", ec);
  });
  if (!s.thread.joinable()) return;
  // A client that never answers the close handshake holds run() for the
  // close timeout; that is the longest stop() takes.
  s.thread.join();
}

uint16_t Server::port() const { return impl_->port; }
const std::string& Server::address() const { return impl_->options.address; }

uint32_t Server::add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema) {
  AdvertisedChannel c;
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    c = AdvertisedChannel{static_cast<uint32_t>(impl_->channels.size() + 1), topic, schema_name, schema};
    impl_->channels.push_back(c);
  }
  impl_->post_to_all(advertise_json({c}));
  return c.id;
}

void Server::set_http_handler(HttpHandler handler) { impl_->http = std::move(handler); }

void Server::accept_client_publish(ClientPublishHandler* handler, std::vector<std::string> topics) {
  impl_->publish_handler = handler;
  impl_->publish_topics = std::move(topics);
}

bool Server::has_subscribers(uint32_t channel) const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  for (const auto& [hdl, c] : impl_->clients) {
    if (c->subscription_of_channel.count(channel) > 0) return true;
  }
  return false;
}

void Server::publish(uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  for (const auto& [hdl, c] : impl_->clients) {
    const auto it = c->subscription_of_channel.find(channel);
    if (it != c->subscription_of_channel.end()) c->queue.push(QueuedMessage{it->second, log_time_ns, json});
  }
}

void Server::publish_to(uint64_t client, uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  for (const auto& [hdl, c] : impl_->clients) {
    if (c->id != client) continue;
    const auto it = c->subscription_of_channel.find(channel);
    if (it != c->subscription_of_channel.end()) c->queue.push(QueuedMessage{it->second, log_time_ns, json});
  }
}

void Server::set_status(const std::string& id, StatusLevel level, const std::string& message) {
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    impl_->statuses[id] = {level, message};
  }
  impl_->post_to_all(status_json(id, level, message));
}

void Server::remove_status(const std::string& id) {
  {
    std::lock_guard<std::mutex> lock(impl_->mu);
    if (impl_->statuses.erase(id) == 0) return;
  }
  impl_->post_to_all(remove_status_json({id}));
}

void Server::set_parameters(std::vector<Parameter> parameters) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->parameters = std::move(parameters);
}

ServerStats Server::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  ServerStats out;
  out.clients = static_cast<int64_t>(impl_->seen.size());
  for (const auto& c : impl_->seen) {
    ClientStats cs = c->stats;
    cs.dropped = c->queue.dropped();
    out.sent += cs.sent;
    out.dropped += cs.dropped;
    out.per_client.push_back(cs);
  }
  return out;
}

}  // namespace rigctl::foxglove
