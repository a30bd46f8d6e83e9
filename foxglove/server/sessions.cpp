#include "foxglove/server/sessions.hpp"

#include <algorithm>
#include <set>

namespace rigctl::foxglove {

void Sessions::accept_client_publish(ClientPublishHandler* handler, std::vector<std::string> topics) {
  publish_handler_ = handler;
  publish_topics_ = std::move(topics);
}

std::shared_ptr<Sessions::Client> Sessions::find(uint64_t id) const {
  const auto it = clients_.find(id);
  return it == clients_.end() ? nullptr : it->second;
}

void Sessions::send_text(Client& c, std::string text) {
  c.queue.push_text(std::make_shared<const std::string>(std::move(text)));
}

void Sessions::send_text_to_all(const std::string& text) {
  const auto shared = std::make_shared<const std::string>(text);
  for (auto& [id, c] : clients_) c->queue.push_text(shared);
}

void Sessions::warn(Client& c, const std::string& id, const std::string& message) {
  refusals_.refuse(id, "client " + c.stats.address + ": " + clip(message, kMaxEchoedChars));
  send_text(c, status_json(id, StatusLevel::kWarning, clip(message, kMaxEchoedChars)));
}

uint64_t Sessions::open(const std::string& address, const std::string& subprotocol) {
  Lock lock(mu_);
  auto c = std::make_shared<Client>(next_id_++, options_.queue_messages, options_.queue_bytes);
  c->stats.address = address;
  c->stats.subprotocol = subprotocol;
  send_text(*c, server_info_json(options_.name, options_.metadata, options_.session_id, client_publish()));
  send_text(*c, advertise_json(channels_));
  for (const auto& [id, status] : statuses_) send_text(*c, status_json(id, status.first, status.second));
  clients_.emplace(c->id, c);
  return c->id;
}

void Sessions::close(uint64_t id) {
  {
    Lock lock(mu_);
    const auto it = clients_.find(id);
    if (it == clients_.end()) return;
    ClientStats s = it->second->stats;
    s.dropped = it->second->queue.dropped();
    closed_sent_ += s.sent;
    closed_dropped_ += s.dropped;
    closed_.push_back(std::move(s));
    if (closed_.size() > kClosedClientsKept) closed_.pop_front();
    clients_.erase(it);  // its queue and subscriptions go with it
  }
  if (publish_handler_ != nullptr) publish_handler_->on_client_closed(id);
}

void Sessions::handle_text(uint64_t id, const std::string& text) {
  const ClientRequest r = parse_client_request(text);
  Lock lock(mu_);
  const auto c = find(id);
  if (!c) return;
  switch (r.kind) {
    case ClientRequest::Kind::kSubscribe: return subscribe(*c, r);
    case ClientRequest::Kind::kUnsubscribe: return unsubscribe(*c, r);
    case ClientRequest::Kind::kAdvertise: return advertise(*c, r);
    case ClientRequest::Kind::kUnadvertise:
      for (const auto channel : r.unadvertised) c->advertised.erase(channel);
      return;
    case ClientRequest::Kind::kGetParameters:
    case ClientRequest::Kind::kSetParameters: return answer_parameters(*c, r);
    case ClientRequest::Kind::kRefused:
      return warn(*c, "refused_" + r.op, "rigctl serves read-only telemetry: '" + r.op + "' is not offered");
    case ClientRequest::Kind::kUnknown:
      return warn(*c, "bad_request", r.error.empty() ? "unknown op '" + r.op + "'" : "unreadable request: " + r.error);
  }
}

void Sessions::subscribe(Client& c, const ClientRequest& r) {
  // Ids must be unique per client, and a channel is subscribed once: a
  // second id for it, or an id in use, is refused (a data message names its
  // subscription, so two meanings for one id would be ambiguous).
  std::set<uint32_t> used;
  for (const auto& [channel, sub] : c.subscription_of_channel) used.insert(sub);
  for (const auto& [sub, channel] : r.subscriptions) {
    if (channel == 0 || channel > channels_.size()) {
      warn(c, "bad_subscription", "channel " + std::to_string(channel) + " was never advertised");
    } else if (used.count(sub) > 0) {
      warn(c, "bad_subscription", "subscription id " + std::to_string(sub) + " is already in use");
    } else if (c.subscription_of_channel.count(channel) > 0) {
      warn(c, "bad_subscription", "channel " + std::to_string(channel) + " is already subscribed");
    } else {
      c.subscription_of_channel[channel] = sub;
      used.insert(sub);
    }
  }
}

void Sessions::unsubscribe(Client& c, const ClientRequest& r) {
  for (const auto sub : r.unsubscriptions) {
    for (auto it = c.subscription_of_channel.begin(); it != c.subscription_of_channel.end();) {
      it = it->second == sub ? c.subscription_of_channel.erase(it) : std::next(it);
    }
  }
}

// Client channels: JSON on one of the accepted topics, or refused.
void Sessions::advertise(Client& c, const ClientRequest& r) {
  for (const auto& ch : r.client_channels) {
    const bool topic_ok = std::find(publish_topics_.begin(), publish_topics_.end(), ch.topic) != publish_topics_.end();
    if (publish_handler_ != nullptr && topic_ok && ch.encoding == "json") {
      c.advertised[ch.id] = ch;
      continue;
    }
    warn(c, "refused_advertise",
         publish_handler_ == nullptr ? "rigctl serves read-only telemetry here: client publishing is not offered"
                                     : "client channel '" + clip(ch.topic, 64) + "' (" + clip(ch.encoding, 32) +
                                           ") refused: only JSON on the console's command topic");
  }
}

void Sessions::answer_parameters(Client& c, const ClientRequest& r) {
  std::vector<Parameter> answer;
  for (const auto& p : parameters_) {
    const bool wanted = r.parameter_names.empty() ||
                        std::find(r.parameter_names.begin(), r.parameter_names.end(), p.name) != r.parameter_names.end();
    if (wanted) answer.push_back(p);
  }
  if (r.kind == ClientRequest::Kind::kSetParameters) {
    send_text(c, status_json("parameters_read_only", StatusLevel::kWarning,
                             "the rig's gains and limits are read-only here: change the rig's config file"));
  }
  send_text(c, parameter_values_json(answer, clip(r.request_id, 64)));
}

// A binary frame: a message on a channel the client advertised, handed to
// the publish handler; anything else is answered with a warning.
void Sessions::handle_binary(uint64_t id, const std::string& frame) {
  const auto data = parse_client_message_data(frame);
  std::string topic;
  {
    Lock lock(mu_);
    const auto c = find(id);
    if (!c) return;
    if (!data) {
      return warn(*c, "bad_client_message", "unreadable binary message: only opcode 1 (client message data) is accepted");
    }
    const auto it = c->advertised.find(data->channel);
    if (it != c->advertised.end()) topic = it->second.topic;
    if (topic.empty() || publish_handler_ == nullptr) {
      return warn(*c, "bad_client_message", "client channel " + std::to_string(data->channel) + " was not advertised");
    }
  }
  publish_handler_->on_client_message(id, topic, data->payload);
}

bool Sessions::pop(uint64_t id, QueuedMessage& out) {
  Lock lock(mu_);
  const auto c = find(id);
  if (!c || !c->queue.pop(out)) return false;
  ++c->stats.sent;
  return true;
}

std::vector<std::pair<uint64_t, std::string>> Sessions::take_overflowed() {
  std::vector<std::pair<uint64_t, std::string>> out;
  Lock lock(mu_);
  for (auto& [id, c] : clients_) {
    if (!c->queue.overflowed() || c->overflow_reported) continue;
    c->overflow_reported = true;
    out.emplace_back(id, "did not read its answers: " + std::to_string(c->queue.size()) + " messages (" +
                             std::to_string(c->queue.bytes() / 1024) + " kB) queued");
    refusals_.refuse("queue_overflow", "client " + c->stats.address + " closed: " + out.back().second);
  }
  return out;
}

std::vector<uint64_t> Sessions::open_ids() const {
  Lock lock(mu_);
  std::vector<uint64_t> ids;
  for (const auto& [id, c] : clients_) ids.push_back(id);
  return ids;
}

std::size_t Sessions::open_count() const {
  Lock lock(mu_);
  return clients_.size();
}

std::string Sessions::address(uint64_t id) const {
  Lock lock(mu_);
  const auto c = find(id);
  return c ? c->stats.address : std::string();
}

uint32_t Sessions::add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema) {
  Lock lock(mu_);
  const AdvertisedChannel c{static_cast<uint32_t>(channels_.size() + 1), topic, schema_name, schema};
  channels_.push_back(c);
  send_text_to_all(advertise_json({c}));
  return c.id;
}

bool Sessions::has_subscribers(uint32_t channel) const {
  Lock lock(mu_);
  for (const auto& [id, c] : clients_) {
    if (c->subscription_of_channel.count(channel) > 0) return true;
  }
  return false;
}

void Sessions::publish(uint32_t channel, uint64_t log_time_ns, const std::shared_ptr<const std::string>& json) {
  Lock lock(mu_);
  for (const auto& [id, c] : clients_) {
    const auto it = c->subscription_of_channel.find(channel);
    if (it != c->subscription_of_channel.end()) c->queue.push_data(it->second, log_time_ns, json);
  }
}

void Sessions::publish_to(uint64_t client, uint32_t channel, uint64_t log_time_ns, std::shared_ptr<const std::string> json) {
  Lock lock(mu_);
  const auto c = find(client);
  if (!c) return;
  const auto it = c->subscription_of_channel.find(channel);
  // An answer is the client's own: queued as text is, never dropped for data.
  if (it != c->subscription_of_channel.end()) {
    c->queue.push_text(std::make_shared<const std::string>(message_data_frame(it->second, log_time_ns, *json)), true);
  }
}

void Sessions::set_status(const std::string& id, StatusLevel level, const std::string& message) {
  Lock lock(mu_);
  statuses_[id] = {level, message};
  send_text_to_all(status_json(id, level, message));
}

void Sessions::remove_status(const std::string& id) {
  Lock lock(mu_);
  if (statuses_.erase(id) == 0) return;
  send_text_to_all(remove_status_json({id}));
}

void Sessions::set_parameters(std::vector<Parameter> parameters) {
  Lock lock(mu_);
  parameters_ = std::move(parameters);
}

ServerStats Sessions::stats() const {
  ServerStats out;
  out.refusals = refusals_.counts();
  Lock lock(mu_);
  out.clients = static_cast<int64_t>(next_id_ - 1);
  out.sent = closed_sent_;
  out.dropped = closed_dropped_;
  out.per_client.assign(closed_.begin(), closed_.end());
  for (const auto& [id, c] : clients_) {
    ClientStats cs = c->stats;
    cs.dropped = c->queue.dropped();
    out.sent += cs.sent;
    out.dropped += cs.dropped;
    out.per_client.push_back(cs);
  }
  return out;
}

}  // namespace rigctl::foxglove
