// A TCP port on 127.0.0.1 that the OS just had free, for a server started
// next (rigctl bench's Foxglove clients, the tests'). Another process could
// take it first; between the few servers of one machine that does not
// happen in practice, and a taken port fails the bind loudly.
#pragma once

namespace rigctl {

// Throws std::runtime_error when the OS gives none.
int free_loopback_port();

}  // namespace rigctl
