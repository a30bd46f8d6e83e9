// The protocol side of the Foxglove server: every connected client's state
// (subscriptions, the channels it publishes on, its one outgoing queue) and
// what each message a client sends does. No sockets: server.cpp moves bytes
// between these and websocketpp, and the fuzzer (tests/fuzz/fuzz_foxglove.cpp)
// drives them directly.
//
// Thread-safe: the server's thread calls open/close/handle_*/pop; publish(),
// set_status() and the rest come from any thread. The publish handler is
// called without the lock held (it may publish answers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "foxglove/server/client_queue.hpp"
#include "foxglove/server/protocol.hpp"
#include "foxglove/server/refusal_log.hpp"
#include "foxglove/server/server.hpp"

namespace rigctl::foxglove {

struct SessionsOptions {
  std::string name = "rigctl";
  std::map<std::string, std::string> metadata;
  std::string session_id;
  std::size_t queue_messages = 1024;
  std::size_t queue_bytes = kMaxClientQueueBytes;
};

class Sessions {
 public:
  explicit Sessions(SessionsOptions options) : options_(std::move(options)) {}

  void accept_client_publish(ClientPublishHandler* handler, std::vector<std::string> topics);
  bool client_publish() const { return publish_handler_ != nullptr; }
  ClientPublishHandler* publish_handler() const { return publish_handler_; }
  RefusalLog& refusals() { return refusals_; }

  // A client whose upgrade succeeded: its greeting (serverInfo, the
  // channels, the active statuses) is queued. Returns its id (never reused).
  uint64_t open(const std::string& address, const std::string& subprotocol);
  // The client is gone: its state freed, its statistics kept for the report.
  void close(uint64_t id);
  void handle_text(uint64_t id, const std::string& text);
  void handle_binary(uint64_t id, const std::string& frame);
  // The client's next queued message (counted as sent).
  bool pop(uint64_t id, QueuedMessage& out);
  // Clients whose queue overflowed since the last call, each with the
  // reason it is to be closed for.
  std::vector<std::pair<uint64_t, std::string>> take_overflowed();
  std::vector<uint64_t> open_ids() const;
  std::size_t open_count() const;
  std::string address(uint64_t id) const;
  // Called by the server when it refuses something of a client (a closed
  // silent client, a message too big): counted and reported.
  void refuse(const std::string& code, const std::string& text) { refusals_.refuse(code, text); }

  // Server's API (server.hpp).
  uint32_t add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema);
  bool has_subscribers(uint32_t channel) const;
  void publish(uint32_t channel, uint64_t log_time_ns, const std::shared_ptr<const std::string>& json);
  void publish_to(uint64_t client, uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json);
  void set_status(const std::string& id, StatusLevel level, const std::string& message);
  void remove_status(const std::string& id);
  void set_parameters(std::vector<Parameter> parameters);
  ServerStats stats() const;

 private:
  struct Client {
    Client(uint64_t i, std::size_t messages, std::size_t bytes) : id(i), queue(messages, bytes) {}
    uint64_t id;
    std::map<uint32_t, uint32_t> subscription_of_channel;
    std::map<uint32_t, ClientChannel> advertised;  // the client's own channels (clientPublish)
    ClientQueue queue;
    ClientStats stats;
    bool overflow_reported = false;
  };
  using Lock = std::lock_guard<std::mutex>;

  std::shared_ptr<Client> find(uint64_t id) const;
  // Under the lock: a text message to one client, or to all.
  void send_text(Client& c, std::string text);
  void send_text_to_all(const std::string& text);
  // A warning status to one client, its message clipped and the refusal counted.
  void warn(Client& c, const std::string& id, const std::string& message);
  void subscribe(Client& c, const ClientRequest& r);
  void unsubscribe(Client& c, const ClientRequest& r);
  void advertise(Client& c, const ClientRequest& r);
  void answer_parameters(Client& c, const ClientRequest& r);

  SessionsOptions options_;
  ClientPublishHandler* publish_handler_ = nullptr;  // set before the first client
  std::vector<std::string> publish_topics_;
  RefusalLog refusals_;

  mutable std::mutex mu_;  // everything below
  std::map<uint64_t, std::shared_ptr<Client>> clients_;
  std::deque<ClientStats> closed_;  // the last kClosedClientsKept
  int64_t closed_sent_ = 0;
  int64_t closed_dropped_ = 0;
  std::vector<AdvertisedChannel> channels_;
  std::map<std::string, std::pair<StatusLevel, std::string>> statuses_;
  std::vector<Parameter> parameters_;
  uint64_t next_id_ = 1;
};

}  // namespace rigctl::foxglove
