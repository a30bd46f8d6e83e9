// The thread that writes a procedure's recovery file (tools/procedure/recovery_file.hpp)
// off the tick. The loop offers a recovery at every cycle, pass and step end
// and at least every 10 s (rt/loop/rig_loop.cpp); the writer keeps the
// newest it finds and writes it (write, fsync, rename).
//
// Paced runs: `offer` never waits; a recovery the writer has not taken yet
// is replaced by the next one, so the file is at most one write behind the
// rig. --fast runs (lockstep): `offer` returns once that recovery is on
// disk, so a kill at any moment finds the file at the last cycle ended or
// the one before (the one being written): a resume repeats at most one cycle.
// Simulated time has no deadline to keep; this is the telemetry queue's
// wait policy applied to the recovery.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "rt/bounded_handoff.hpp"
#include "rt/procedure/recovery_sink.hpp"
#include "tools/procedure/recovery_file.hpp"

namespace rigctl {

class RecoveryWriter final : public RecoverySink {
 public:
  // on_written: after each file is on disk, on the writer's thread (the
  // rainflow matrices at block ends); may be empty.
  RecoveryWriter(std::string path, RecoveryIdentity identity, bool lockstep,
                 std::function<void(const ProcedureRecovery&)> on_written = {});
  ~RecoveryWriter() override;

  void start();
  // Writes what is still queued, then ends the thread.
  void stop();
  void offer(const ProcedureRecovery& recovery) noexcept override;

  const std::string& path() const { return path_; }
  int64_t files_written() const { return written_count_.load(); }
  // The last write error (empty: none); the rig keeps running without it.
  std::string error() const;

 private:
  void run();
  bool drain();  // writes the newest queued recovery; false: nothing queued

  std::string path_;
  RecoveryIdentity identity_;
  bool lockstep_;
  std::function<void(const ProcedureRecovery&)> on_written_;
  BoundedHandoff<ProcedureRecovery> queue_;
  std::unique_ptr<ProcedureRecovery> newest_;  // the writer's scratch
  std::atomic<uint64_t> written_sequence_{0};
  std::atomic<int64_t> written_count_{0};
  std::atomic<bool> running_{false};
  std::atomic<bool> failed_{false};
  std::string error_;  // set once, before failed_
  std::thread thread_;
};

}  // namespace rigctl
