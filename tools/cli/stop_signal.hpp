// SIGINT and SIGTERM as a request to stop, for the subcommands with a clean
// way down (a run closes its logs, a rig-sim its sockets). Those without one
// leave the signals alone, so a signal ends them at once as it always did.
#pragma once

#include <atomic>

namespace rigctl::cli {

// From this call on, SIGINT and SIGTERM set the returned flag instead of
// ending the process. The flag is the process's one, read from any thread.
const std::atomic<bool>& stop_on_signals();

}  // namespace rigctl::cli
