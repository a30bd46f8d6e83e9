#include "foxglove/console/console_control.hpp"

namespace rigctl::foxglove {

bool ConsoleControl::claim(uint64_t client, const std::string& sender, int64_t now_utime) {
  if (holder_ && *holder_ != client) return false;
  if (!holds(client)) since_utime_ = now_utime;
  holder_ = client;
  holder_sender_ = sender;
  return true;
}

bool ConsoleControl::release(uint64_t client) {
  if (!holds(client)) return false;
  holder_.reset();
  holder_sender_.clear();
  since_utime_ = 0;
  return true;
}

}  // namespace rigctl::foxglove
