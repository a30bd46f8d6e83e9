// systemd readiness and watchdog (tools/run/service_notify.hpp): READY=1 only
// once the loop has ticked, WATCHDOG=1 only while its tick count moves, and
// `rigctl run` under a NOTIFY_SOCKET the test owns sends READY=1, then
// periodic WATCHDOG=1, then STOPPING=1.
#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "background_process.hpp"
#include "config_edit.hpp"
#include "tools/run/service_notify.hpp"

namespace fs = std::filesystem;

namespace {

// A unix datagram socket standing in for systemd's notify socket.
class NotifySocket {
 public:
  NotifySocket() {
    path_ = (fs::temp_directory_path() / ("rigctl_notify_" + std::to_string(::getpid()) + "_" + std::to_string(n_++))).string();
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path_.c_str());
    ::unlink(path_.c_str());
    ok_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~NotifySocket() {
    if (fd_ >= 0) ::close(fd_);
    ::unlink(path_.c_str());
  }
  bool ok() const { return ok_; }
  const std::string& path() const { return path_; }

  // The next message, "" when none arrived within timeout_ms.
  std::string receive(int timeout_ms) {
    timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char buf[4096];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  static inline int n_ = 0;
  std::string path_;
  int fd_ = -1;
  bool ok_ = false;
};

// Sets the systemd variables for the scope (this process and its children).
struct NotifyEnvironment {
  NotifyEnvironment(const std::string& socket, const std::string& watchdog_usec) {
    ::setenv("NOTIFY_SOCKET", socket.c_str(), 1);
    ::setenv("WATCHDOG_USEC", watchdog_usec.c_str(), 1);
    ::unsetenv("WATCHDOG_PID");  // unset: the watchdog is for whichever process reads it
  }
  ~NotifyEnvironment() {
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
  }
};

TEST(ServiceNotifier, ReadyAfterTheFirstTickAndPingsOnlyWhileTicking) {
  NotifySocket sock;
  ASSERT_TRUE(sock.ok()) << sock.path();
  NotifyEnvironment env(sock.path(), "200000");
  std::atomic<int64_t> beats{0};
  rigctl::ServiceNotifier n(beats);
  ASSERT_TRUE(n.active());
  EXPECT_EQ(n.watchdog_usec(), 200000u);

  EXPECT_EQ(n.poll_once(), "");  // the loop has not ticked: not ready
  beats = 1;
  EXPECT_NE(n.poll_once().find("READY=1"), std::string::npos);
  EXPECT_NE(sock.receive(1000).find("READY=1"), std::string::npos);
  EXPECT_EQ(n.poll_once(), "");  // no tick since: a stuck loop gets no ping
  beats = 5;
  EXPECT_EQ(n.poll_once(), "WATCHDOG=1");
  EXPECT_EQ(sock.receive(1000), "WATCHDOG=1");
  EXPECT_EQ(n.poll_once(), "");
  EXPECT_EQ(sock.receive(100), "");  // and nothing was sent
}

TEST(ServiceNotifier, InactiveOutsideSystemd) {
  ::unsetenv("NOTIFY_SOCKET");
  std::atomic<int64_t> beats{1};
  rigctl::ServiceNotifier n(beats);
  EXPECT_FALSE(n.active());
  EXPECT_EQ(n.poll_once(), "");
}

TEST(ServiceWatchdog, RigctlRunSendsReadyThenPeriodicWatchdogThenStopping) {
  NotifySocket sock;
  ASSERT_TRUE(sock.ok()) << sock.path();
  const fs::path dir = fs::temp_directory_path() / ("rigctl_watchdog_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // Paced at normal priority: overruns only indicate (tests/support/config_edit.hpp),
  // so the run ends as the profile says and exits 0 on a loaded machine too.
  const std::string config = (dir / "rig.yaml").string();
  std::ofstream(config) << rigctl::test::without_overrun_stop(rigctl::test::shipped_config());
  std::vector<std::string> messages;
  int status = -1;
  {
    NotifyEnvironment env(sock.path(), "200000");  // pings every 100 ms
    rigctl::test::BackgroundProcess rig({RIGCTL_BINARY, "run", config, "--duration", "2", "--no-realtime", "--log",
                                         (dir / "run.lcm").string()},
                                        (dir / "out.txt").string());
    // Until STOPPING=1, or 30 s of silence (a hung run fails the test).
    for (std::string m = sock.receive(30000); !m.empty(); m = sock.receive(30000)) {
      messages.push_back(m);
      if (m.rfind("STOPPING=1", 0) == 0) break;
    }
    status = rig.wait();
    EXPECT_EQ(status, 0) << rig.output();
  }
  fs::remove_all(dir);
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().rfind("READY=1", 0), 0u) << messages.front();
  std::size_t pings = 0;
  for (std::size_t i = 1; i + 1 < messages.size(); ++i) {
    EXPECT_EQ(messages[i], "WATCHDOG=1") << "message " << i;
    pings += messages[i] == "WATCHDOG=1";
  }
  // A 2 s run pinged every 100 ms: far more than 3, whatever the load.
  EXPECT_GE(pings, 3u);
  EXPECT_EQ(messages.back().rfind("STOPPING=1", 0), 0u) << messages.back();
}

}  // namespace
