// `rigctl cmd`: sends one authenticated operator command to a rig and waits
// for its acknowledgement (docs/operator-commands.md).
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

namespace rigctl {

// Exit codes of `rigctl cmd`.
inline constexpr int kCmdAccepted = 0;   // the rig acknowledged (or, with --wait-ack 0, the command was sent)
inline constexpr int kCmdError = 1;      // nothing sent, or sending failed: key file, state file, LCM
inline constexpr int kCmdUsage = 2;      // bad command line
inline constexpr int kCmdRejected = 3;   // the rig replied: rejected, with the reason
inline constexpr int kCmdNoAck = 4;      // no valid acknowledgement within the wait

struct CmdOptions {
  std::string command;           // arm start hold resume stop reset hydraulics-low hydraulics-high hydraulics-off setpoint
  std::string value;             // setpoint only: the new setpoint, SI units
  std::string key_path;          // required
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=1";  // the rig network (docs/running.md, Telemetry)
  std::string channel = "RIGCTL_OPERATOR";
  std::string ack_channel;       // "": <channel>_ACK
  std::string sender;            // "": USER@HOSTNAME, cleaned to a valid sender id
  double wait_ack_s = 2.0;       // 0: send and do not wait
  std::string state_path;        // "": default_sequence_state_path(sender)
};

// $XDG_STATE_HOME/rigctl/<sender>.seq, else ~/.local/state/rigctl/<sender>.seq.
// Throws when neither XDG_STATE_HOME nor HOME is set.
std::string default_sequence_state_path(const std::string& sender);

// Reserves the next sequence number, max(last + 1, now_utime), and stores it
// in the state file before anything is sent (a crash after sending must not
// reuse it). flock() serialises concurrent invocations. Using the wall clock
// as a floor keeps the sequence increasing even when the state file is lost
// or a new one is started; the file keeps it increasing when the clock steps
// back. Throws std::runtime_error naming the file.
int64_t reserve_sequence(const std::string& state_path, int64_t now_utime);

// Parses, signs, sends, waits; prints one line on `out` (result) or `err`
// (errors). Returns one of the exit codes above.
int run_cmd_command(const CmdOptions& options, std::ostream& out, std::ostream& err);

}  // namespace rigctl
