// A network namespace a test creates for multicast (LCM's udpm://): loopback
// up with multicast on and a multicast route, deleted again at the end. The
// tests never send or join multicast in the host's namespace: a thread that
// uses sockets joins the namespace first and checks that it did.
#pragma once

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "process.hpp"

namespace rigctl::test {

class TestNetns {
 public:
  // Creates rigctl-<tag>-<pid>. On failure skip_reason() says why (not root,
  // no iproute2, a step refused): the test skips with it.
  explicit TestNetns(const std::string& tag) : name_("rigctl-" + tag + "-" + std::to_string(::getpid())) {
    if (::geteuid() != 0) {
      skip_reason_ = "needs root to create a network namespace";
      return;
    }
    if (run_command("ip -V").exit_code != 0) {
      skip_reason_ = "no 'ip' program (iproute2) on PATH";
      return;
    }
    for (const std::string& step : {"ip netns add " + name_, exec_prefix() + "ip link set lo up",
                                    exec_prefix() + "ip link set lo multicast on",
                                    exec_prefix() + "ip route add 224.0.0.0/4 dev lo"}) {
      const auto r = run_command(step);
      if (r.exit_code != 0) {
        skip_reason_ = "cannot set up a network namespace: '" + step + "' exited " + std::to_string(r.exit_code) +
                       ": " + r.output;
        return;
      }
      created_ = true;
    }
  }
  ~TestNetns() {
    if (created_) run_command("ip netns del " + name_);
  }
  TestNetns(const TestNetns&) = delete;
  TestNetns& operator=(const TestNetns&) = delete;

  bool ready() const { return skip_reason_.empty(); }
  const std::string& skip_reason() const { return skip_reason_; }
  const std::string& name() const { return name_; }
  // Prefix of a shell command that runs inside the namespace.
  std::string exec_prefix() const { return "ip netns exec " + name_ + " "; }

  // Moves the calling thread into the namespace (setns changes only the
  // calling thread; threads it starts inherit it) and checks that it is
  // there before any multicast. "" or the reason it is not.
  std::string enter_this_thread() const {
    const std::string ns_file = "/var/run/netns/" + name_;
    const int fd = ::open(ns_file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return "open " + ns_file + ": " + std::strerror(errno);
    const int rc = ::setns(fd, CLONE_NEWNET);
    ::close(fd);
    if (rc != 0) return std::string("setns: ") + std::strerror(errno);
    struct stat want{}, have{};
    if (::stat(ns_file.c_str(), &want) != 0 || ::stat("/proc/thread-self/ns/net", &have) != 0 ||
        want.st_ino != have.st_ino) {
      return "thread is not in network namespace " + name_ + ": refusing to use multicast";
    }
    return "";
  }

 private:
  std::string name_;
  std::string skip_reason_;
  bool created_ = false;
};

}  // namespace rigctl::test
