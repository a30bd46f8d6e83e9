// Which requests may open the console's page or a WebSocket: the Host a
// browser asked for must name this server, and the Origin of the page
// that opens a WebSocket must be this server's own or an allowed one.
//
// Why: a page from any site, open in a browser on the rig's PC or the lab
// network, may open a WebSocket to 127.0.0.1 (browsers do not apply the
// same-origin policy to WebSockets, they only send the Origin), read the
// live data and, in operator mode, publish on the console's topic. A site
// whose name resolves to 127.0.0.1 (DNS rebinding) sends its own name as
// Host. Clients that are no browser page (Foxglove's and PlotJuggler's
// desktop apps, rigctl's own) send no Origin and are not concerned.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace rigctl::foxglove {

class OriginPolicy {
 public:
  // The server's address and port, and the origins (scheme://host[:port])
  // allowed besides its own, e.g. a reverse proxy's. Bound to every
  // interface (0.0.0.0, ::), every address of the machine and its host name
  // are the server's too.
  OriginPolicy(const std::string& address, uint16_t port, const std::vector<std::string>& allowed_origins);

  // "" when allowed, else why not (the 403's body). `origin` "" when the
  // request has none.
  std::string check(const std::string& host, const std::string& origin) const;

  // An origin as compared: lower case, no trailing '/'. "" if `text` is no
  // origin (scheme http or https, a host, an optional port, no path).
  static std::string normalise_origin(const std::string& text);

 private:
  std::set<std::string> hosts_;    // Host header values that name this server (lower case)
  std::set<std::string> origins_;  // allowed origins besides the server's own pages
};

}  // namespace rigctl::foxglove
