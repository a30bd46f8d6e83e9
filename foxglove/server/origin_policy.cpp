#include "foxglove/server/origin_policy.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>

namespace rigctl::foxglove {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// host:port as a Host header writes it ([v6]:port).
std::string host_port(const std::string& host, uint16_t port) {
  const bool v6 = host.find(':') != std::string::npos;
  return (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

bool is_loopback(const std::string& a) { return a.rfind("127.", 0) == 0 || a == "::1"; }
bool is_any(const std::string& a) { return a == "0.0.0.0" || a == "::"; }

// Every address of the machine's interfaces, as text.
std::vector<std::string> interface_addresses() {
  std::vector<std::string> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return out;
  for (const ifaddrs* i = list; i != nullptr; i = i->ifa_next) {
    if (i->ifa_addr == nullptr) continue;
    char text[INET6_ADDRSTRLEN] = {};
    if (i->ifa_addr->sa_family == AF_INET) {
      ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr, text, sizeof text);
    } else if (i->ifa_addr->sa_family == AF_INET6) {
      ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr, text, sizeof text);
    } else {
      continue;
    }
    out.emplace_back(text);
  }
  ::freeifaddrs(list);
  return out;
}

}  // namespace

std::string OriginPolicy::normalise_origin(const std::string& text) {
  std::string o = lower(text);
  while (!o.empty() && o.back() == '/') o.pop_back();
  const auto scheme_end = o.find("://");
  if (scheme_end == std::string::npos) return "";
  const std::string scheme = o.substr(0, scheme_end);
  const std::string rest = o.substr(scheme_end + 3);
  if ((scheme != "http" && scheme != "https") || rest.empty()) return "";
  const bool ok = std::all_of(rest.begin(), rest.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == ':' || c == '[' || c == ']';
  });
  return ok ? o : "";
}

OriginPolicy::OriginPolicy(const std::string& address, uint16_t port, const std::vector<std::string>& allowed_origins) {
  std::vector<std::string> names{address};
  if (is_loopback(address) || is_any(address)) names.insert(names.end(), {"localhost", "127.0.0.1", "::1"});
  if (is_any(address)) {
    for (const auto& a : interface_addresses()) names.push_back(a);
    char name[256] = {};
    if (::gethostname(name, sizeof name - 1) == 0 && name[0] != '\0') names.emplace_back(name);
  }
  for (const auto& n : names) hosts_.insert(lower(host_port(n, port)));
  for (const auto& text : allowed_origins) {
    const std::string o = normalise_origin(text);
    if (o.empty()) continue;  // the config reader refuses these with a message
    origins_.insert(o);
    // Behind a proxy that passes the browser's Host on: the origin's host,
    // with and without its port.
    const std::string authority = o.substr(o.find("://") + 3);
    hosts_.insert(authority);
    if (authority.find(':') == std::string::npos || authority.back() == ']') {
      hosts_.insert(authority + (o.rfind("https", 0) == 0 ? ":443" : ":80"));
    }
  }
}

std::string OriginPolicy::check(const std::string& host, const std::string& origin) const {
  const std::string h = lower(host);
  if (hosts_.count(h) == 0) {
    return "Host '" + host.substr(0, 100) + "' does not name this server (a page of another site cannot use it)";
  }
  if (origin.empty()) return "";  // no browser page: a desktop client or a script
  const std::string o = lower(origin);
  if (origins_.count(o) > 0) return "";
  // The server's own page: its origin is the Host it was loaded from.
  if (o == "http://" + h || o == "https://" + h) return "";
  return "Origin '" + origin.substr(0, 100) +
         "' is not allowed: only this server's own page, or an origin listed in telemetry.websocket.allowed_origins";
}

}  // namespace rigctl::foxglove
