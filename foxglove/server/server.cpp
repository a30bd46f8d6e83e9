// The Foxglove WebSocket server on websocketpp with standalone asio: the
// sockets, the handshake's checks, the timers. What a client's messages do
// is sessions.cpp's. Every socket operation and every map below runs on the
// server's one thread; other threads only reach the sessions (under their
// mutex).
#include "foxglove/server/server.hpp"

#include <malloc.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>

#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include "foxglove/server/origin_policy.hpp"
#include "foxglove/server/protocol.hpp"
#include "foxglove/server/sessions.hpp"

namespace rigctl::foxglove {

namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;
using Clock = std::chrono::steady_clock;

// Bytes a client's socket may have queued in websocketpp before the server
// stops handing it more: about a quarter second of every channel at 400 Hz.
// Past it the client is not keeping up and its messages wait in its own
// bounded queue, which drops the oldest data.
constexpr std::size_t kMaxSocketBacklog = 256 * 1024;
// The kernel's share of a client's backlog (it doubles the value): with
// websocketpp's share above and the client's own queue, a client that stops
// reading holds about a second of data, and one 50 ms away still gets
// 2.5 MB/s, eight times what every channel at 400 Hz needs. Left to itself
// the kernel would grow it to megabytes: ten seconds of stale data.
constexpr int kSocketSendBuffer = 128 * 1024;
// A client that does not answer the close handshake is not waited for longer.
constexpr long kCloseTimeoutMs = 1000;
// A connection that has not completed its HTTP request (a page or an
// upgrade) in this time is closed: a browser sends it at once.
constexpr long kOpenHandshakeTimeoutMs = 5000;
// Connections still in their HTTP request at once. Past it the oldest is
// closed to make room, so a flood of idle connections cannot lock a
// console out (a console's request completes within milliseconds of its
// connect) and the process keeps file descriptors to spare. 64: a browser
// opens up to 6 per host for a page's files, times a control room's
// consoles reconnecting together, with room.
constexpr std::size_t kMaxPendingConnections = 64;
// The body of a plain HTTP request: only GETs are answered.
constexpr std::size_t kMaxHttpBodyBytes = 1024;
// After a failed accept (out of file descriptors) the next waits this
// long rather than retrying at once, which would spin.
constexpr auto kAcceptRetry = std::chrono::milliseconds(100);
// How often the clients' queues go onto their sockets. Every 5 ms is two
// ticks of every channel per write at 400 Hz: a fraction of the wake-ups of
// the server, the clients and the kernel's loopback that a write per message
// would cost, on a machine whose other core runs the loop, for at most 5 ms
// of the 50 ms a client may lag. A client whose socket was full is tried
// again at the next flush.
constexpr auto kFlushInterval = std::chrono::milliseconds(5);

}  // namespace

struct Server::Impl {
  ServerOptions options;
  WsServer ws;
  std::thread thread;
  uint16_t port = 0;
  Sessions sessions;
  std::optional<OriginPolicy> origins;  // once the port is known
  std::unique_ptr<asio::steady_timer> flush_timer, ping_timer, accept_timer;
  HttpHandler http;  // set before start()
  bool stopped = false;  // under stop_mu
  std::mutex stop_mu;
  std::atomic<bool> stopping{false};  // the timers must not re-arm once set

  // The server's thread only.
  std::map<Hdl, uint64_t, std::owner_less<Hdl>> id_of;
  std::map<uint64_t, Hdl> hdl_of;
  std::map<uint64_t, Clock::time_point> last_pong;
  std::map<Hdl, bool, std::owner_less<Hdl>> admitted;  // upgrades accepted, until closed
  std::set<uint64_t> closing;                           // closed by the server, not yet gone
  std::deque<std::weak_ptr<WsServer::connection_type>> pending;

  Impl(ServerOptions o, SessionsOptions so) : options(std::move(o)), sessions(std::move(so)) {}

  static std::string peer(const WsServer::connection_ptr& con) { return con->get_remote_endpoint(); }

  // An upgrade: this server's Host and Origin, a free client slot, a subprotocol it speaks.
  bool validate(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    const std::string why = origins->check(con->get_request_header("Host"), con->get_request_header("Origin"));
    if (!why.empty()) {
      sessions.refuse("origin", "upgrade from " + peer(con) + " refused (403): " + why);
      con->set_status(websocketpp::http::status_code::forbidden);
      con->set_body(why + "\n");
      return false;
    }
    if (admitted.size() >= options.max_clients) {
      sessions.refuse("too_many_clients", "upgrade from " + peer(con) + " refused (503): " +
                                              std::to_string(options.max_clients) + " clients connected");
      con->set_status(websocketpp::http::status_code::service_unavailable);
      con->set_body("rigctl serves at most " + std::to_string(options.max_clients) +
                    " clients at once (telemetry.websocket.max_clients); close one and connect again\n");
      return false;
    }
    const auto chosen = choose_subprotocol(con->get_requested_subprotocols());
    if (!chosen) {
      con->set_status(websocketpp::http::status_code::bad_request);
      con->set_body("rigctl speaks the Foxglove WebSocket protocol: ask for subprotocol foxglove.websocket.v1 or foxglove.sdk.v1\n");
      return false;
    }
    con->select_subprotocol(*chosen);
    admitted[hdl] = true;
    return true;
  }

  void on_open(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    const uint64_t id = sessions.open(peer(con), con->get_subprotocol());
    id_of[hdl] = id;
    hdl_of[id] = hdl;
    last_pong[id] = Clock::now();
    flush_one(id, hdl);  // the greeting at once
  }

  void on_close(const Hdl& hdl) {
    admitted.erase(hdl);
    const auto it = id_of.find(hdl);
    if (it == id_of.end()) return;  // a handshake that failed: never opened
    const uint64_t id = it->second;
    websocketpp::lib::error_code ec;
    auto con = ws.get_con_from_hdl(hdl, ec);
    if (!ec && con->get_local_close_code() == websocketpp::close::status::message_too_big) {
      sessions.refuse("message_too_big", "client " + sessions.address(id) + " closed: a message over " +
                                             std::to_string(kMaxMessageBytes / 1024) + " kB");
    }
    id_of.erase(it);
    hdl_of.erase(id);
    last_pong.erase(id);
    closing.erase(id);
    sessions.close(id);
    // Give the freed queue (up to kMaxClientQueueBytes) and buffers back
    // to the system: glibc keeps freed memory in the thread's arena
    // otherwise, and a process that served a flood would stay at its high
    // water mark. Closes are rare; the trim takes well under a millisecond
    // and the loop, which never allocates, does not wait for it.
    ::malloc_trim(0);
  }

  void on_message(const Hdl& hdl, const WsServer::message_ptr& msg) {
    const auto it = id_of.find(hdl);
    if (it == id_of.end()) return;
    if (msg->get_opcode() == websocketpp::frame::opcode::text) {
      sessions.handle_text(it->second, msg->get_payload());
    } else {
      sessions.handle_binary(it->second, msg->get_payload());
    }
  }

  void on_http(const Hdl& hdl) {
    auto con = ws.get_con_from_hdl(hdl);
    const std::string why = origins->check(con->get_request_header("Host"), con->get_request_header("Origin"));
    if (!why.empty()) {
      sessions.refuse("origin", "page request from " + peer(con) + " refused (403): " + why);
      con->set_status(websocketpp::http::status_code::forbidden);
      con->set_body(why + "\n");
      return;
    }
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

  // One client's queue onto its socket while the socket keeps up.
  void flush_one(uint64_t id, const Hdl& hdl) {
    websocketpp::lib::error_code ec;
    auto con = ws.get_con_from_hdl(hdl, ec);
    if (ec || con->get_state() != websocketpp::session::state::open) return;
    QueuedMessage m;
    while (con->get_buffered_amount() < kMaxSocketBacklog && sessions.pop(id, m)) {
      if (m.data) {
        con->send(message_data_frame(m.subscription, m.log_time_ns, *m.payload), websocketpp::frame::opcode::binary);
      } else {
        con->send(*m.payload, m.binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text);
      }
    }
  }

  void flush() {
    for (const auto& [id, hdl] : hdl_of) {
      if (closing.count(id) == 0) flush_one(id, hdl);
    }
    for (const auto& [id, why] : sessions.take_overflowed()) close_client(id, websocketpp::close::status::policy_violation, why);
  }

  void close_client(uint64_t id, websocketpp::close::status::value code, const std::string& why) {
    const auto it = hdl_of.find(id);
    if (it == hdl_of.end() || !closing.insert(id).second) return;
    websocketpp::lib::error_code ec;
    ws.close(it->second, code, clip(why, 100), ec);  // a close reason is at most 123 bytes
  }

  // Every ping interval: clients silent too long are closed, the rest are
  // told of their silence (the console releases a silent holder's control)
  // and pinged.
  void ping_all() {
    const auto now = Clock::now();
    std::vector<std::pair<uint64_t, double>> silent, gone;
    for (const auto& [id, hdl] : hdl_of) {
      if (closing.count(id) > 0) continue;
      const double s = std::chrono::duration<double>(now - last_pong[id]).count();
      if (s >= options.client_timeout_s) {
        gone.emplace_back(id, s);
        continue;
      }
      if (s > options.ping_interval_s) silent.emplace_back(id, s);
      websocketpp::lib::error_code ec;
      ws.ping(hdl, "", ec);
    }
    // After the loop: a close may end the connection at once, and its
    // handler changes the maps.
    for (const auto& [id, s] : gone) {
      sessions.refuse("unresponsive", "client " + sessions.address(id) + " closed: no answer to pings for " +
                                          std::to_string(static_cast<int>(s)) + " s");
      close_client(id, websocketpp::close::status::policy_violation, "no answer to pings");
    }
    if (ClientPublishHandler* h = sessions.publish_handler()) {
      for (const auto& [id, s] : silent) h->on_client_silent(id, s);
    }
  }

  void on_pong(const Hdl& hdl) {
    const auto it = id_of.find(hdl);
    if (it != id_of.end()) last_pong[it->second] = Clock::now();
  }

  // Our own accept loop, rather than websocketpp's: it backs off after a
  // failed accept instead of retrying at once, and it bounds the
  // connections that have not finished their HTTP request.
  void accept_next() {
    if (stopping.load()) return;
    websocketpp::lib::error_code ec;
    WsServer::connection_ptr con = ws.get_connection();
    if (!con) return retry_accept("no connection object");
    ws.async_accept(std::static_pointer_cast<WsServer::transport_con_type>(con),
                    [this, con](const websocketpp::lib::error_code& e) { on_accept(con, e); }, ec);
    if (ec) con->terminate(ec);  // not listening any more: stopped
  }

  void on_accept(const WsServer::connection_ptr& con, const websocketpp::lib::error_code& ec) {
    if (ec) {
      con->terminate(ec);
      if (ec == websocketpp::error::operation_canceled || stopping.load()) return;
      return retry_accept(ec.message());
    }
    bound_pending(con);
    con->start();
    accept_next();
  }

  void retry_accept(const std::string& why) {
    sessions.refuse("accept_failed", "accepting a connection failed (" + why + "); trying again in 100 ms");
    accept_timer->expires_after(kAcceptRetry);
    accept_timer->async_wait([this](const asio::error_code& e) {
      if (!e) accept_next();
    });
  }

  void bound_pending(const WsServer::connection_ptr& con) {
    std::deque<std::weak_ptr<WsServer::connection_type>> still;
    for (const auto& w : pending) {
      const auto p = w.lock();
      if (p && p->get_state() == websocketpp::session::state::connecting) still.push_back(w);
    }
    pending.swap(still);
    while (pending.size() >= kMaxPendingConnections) {
      if (const auto oldest = pending.front().lock()) {
        sessions.refuse("pending_closed", "connection from " + peer(oldest) + " closed before its request: " +
                                              std::to_string(kMaxPendingConnections) + " connections waiting");
        asio::error_code e;
        oldest->get_raw_socket().close(e);  // its pending read fails and websocketpp frees it
      }
      pending.pop_front();
    }
    pending.push_back(con);
  }

  void arm(asio::steady_timer& timer, Clock::duration every, void (Impl::*step)()) {
    timer.expires_after(every);
    timer.async_wait([this, &timer, every, step](const asio::error_code& ec) {
      // Cancelled, or it fired just as stop() cancelled it: not again, or
      // the server's thread would never run out of work.
      if (ec || stopping.load()) return;
      (this->*step)();
      arm(timer, every, step);
    });
  }
};

namespace {

SessionsOptions sessions_options(const ServerOptions& o) {
  SessionsOptions s;
  s.name = o.name;
  s.metadata = o.metadata;
  s.session_id = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
  s.queue_messages = o.client_queue_messages;
  return s;
}

}  // namespace

Server::Server(ServerOptions options) : impl_(std::make_unique<Impl>(options, sessions_options(options))) {
  Impl& s = *impl_;
  s.ws.clear_access_channels(websocketpp::log::alevel::all);
  s.ws.clear_error_channels(websocketpp::log::elevel::all);
  s.ws.init_asio();
  s.ws.set_reuse_addr(true);
  s.ws.set_user_agent("rigctl");  // the Server header: no library name or version to look up
  s.ws.set_close_handshake_timeout(kCloseTimeoutMs);
  s.ws.set_open_handshake_timeout(kOpenHandshakeTimeoutMs);
  s.ws.set_max_message_size(kMaxMessageBytes);
  s.ws.set_max_http_body_size(kMaxHttpBodyBytes);
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
  s.ws.set_message_handler([&s](Hdl hdl, WsServer::message_ptr m) { s.on_message(hdl, m); });
  s.ws.set_http_handler([&s](Hdl hdl) { s.on_http(hdl); });
  s.ws.set_pong_handler([&s](Hdl hdl, const std::string&) { s.on_pong(hdl); });
  const std::string where = s.options.address + ":" + std::to_string(s.options.port);
  try {
    asio::error_code ec;
    const auto address = asio::ip::make_address(s.options.address, ec);
    if (ec) throw std::runtime_error("'" + s.options.address + "' is not an IP address");
    s.ws.listen(asio::ip::tcp::endpoint(address, s.options.port));
    const auto local = s.ws.get_local_endpoint(ec);
    if (ec) throw std::runtime_error(ec.message());
    s.port = local.port();
  } catch (const websocketpp::exception& e) {
    throw std::runtime_error("foxglove server: cannot listen on " + where + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error("foxglove server: cannot listen on " + where + ": " + e.what());
  }
  s.origins.emplace(s.options.address, s.port, s.options.allowed_origins);
  for (auto* t : {&s.flush_timer, &s.ping_timer, &s.accept_timer}) *t = std::make_unique<asio::steady_timer>(s.ws.get_io_service());
}

Server::~Server() { stop(); }

void Server::start() {
  Impl& s = *impl_;
  if (s.thread.joinable()) return;
  s.accept_next();
  s.arm(*s.flush_timer, kFlushInterval, &Impl::flush);
  const auto ping = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s.options.ping_interval_s));
  s.arm(*s.ping_timer, ping, &Impl::ping_all);
  s.thread = std::thread([&s] { s.ws.run(); });
}

void Server::stop() {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.stop_mu);
    if (s.stopped) return;
    s.stopped = true;
  }
  s.stopping.store(true);
  // On the server's thread: stop accepting, close every client, cancel the
  // timers; run() returns once nothing is left to do.
  asio::post(s.ws.get_io_service(), [&s] {
    websocketpp::lib::error_code ec;
    s.ws.stop_listening(ec);
    for (auto* t : {&s.flush_timer, &s.ping_timer, &s.accept_timer}) (*t)->cancel();
    const auto open = s.hdl_of;  // a close may end a connection at once, and its handler changes the map
    for (const auto& [id, hdl] : open) s.ws.close(hdl, websocketpp::close::status::going_away, "rigctl stops", ec);
  });
  if (!s.thread.joinable()) return;
  // A client that never answers the close handshake holds run() for the
  // close timeout; that is the longest stop() takes.
  s.thread.join();
}

uint16_t Server::port() const { return impl_->port; }
const std::string& Server::address() const { return impl_->options.address; }

uint32_t Server::add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema) {
  return impl_->sessions.add_channel(topic, schema_name, schema);
}

void Server::set_http_handler(HttpHandler handler) { impl_->http = std::move(handler); }

void Server::accept_client_publish(ClientPublishHandler* handler, std::vector<std::string> topics) {
  impl_->sessions.accept_client_publish(handler, std::move(topics));
}

void Server::set_refusal_handler(RefusalHandler handler) { impl_->sessions.refusals().set_handler(std::move(handler)); }

bool Server::has_subscribers(uint32_t channel) const { return impl_->sessions.has_subscribers(channel); }

void Server::publish(uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json) {
  impl_->sessions.publish(channel, log_time_ns, json);
}

void Server::publish_to(uint64_t client, uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json) {
  impl_->sessions.publish_to(client, channel, log_time_ns, std::move(json));
}

void Server::set_status(const std::string& id, StatusLevel level, const std::string& message) {
  impl_->sessions.set_status(id, level, message);
}

void Server::remove_status(const std::string& id) { impl_->sessions.remove_status(id); }

void Server::set_parameters(std::vector<Parameter> parameters) { impl_->sessions.set_parameters(std::move(parameters)); }

ServerStats Server::stats() const { return impl_->sessions.stats(); }

Sessions& Server::sessions() { return impl_->sessions; }

}  // namespace rigctl::foxglove
