// Exclusive control of the rig from the browser console (docs/console.md):
// one console at a time may send the commands that move the rig, the others
// watch, as on an industrial station. Stop and hold are not subject to it:
// every console (and `rigctl cmd`) may always send them.
//
// Taking control is a signed claim ("take_control"), verified by the
// operator verifier like any command (rt/comms: CommandIntake::claim, the
// same tag, staleness and replay table); this only says which connection
// holds control once a claim is authentic. Server's thread only.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace rigctl::foxglove {

inline constexpr const char* kTakeControlCommand = "take_control";

class ConsoleControl {
 public:
  // An authentic claim by `sender` on connection `client` at `now_utime`:
  // true when the connection holds control now (it may already have),
  // false while another connection holds it (control passes only when its
  // holder releases it, closes or falls silent).
  bool claim(uint64_t client, const std::string& sender, int64_t now_utime);
  bool holds(uint64_t client) const { return holder_ && *holder_ == client; }
  // False when `client` did not hold control.
  bool release(uint64_t client);
  std::optional<uint64_t> holder() const { return holder_; }
  const std::string& holder_sender() const { return holder_sender_; }
  int64_t since_utime() const { return since_utime_; }  // when the holder took it [us since the epoch]

 private:
  std::optional<uint64_t> holder_;
  std::string holder_sender_;
  int64_t since_utime_ = 0;
};

}  // namespace rigctl::foxglove
