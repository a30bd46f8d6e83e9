// A program started by a test in the background, its output in a file, so
// the test can wait for a line, read what it printed and stop it by pid.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "read_file.hpp"

namespace rigctl::test {

class BackgroundProcess {
 public:
  BackgroundProcess(const std::vector<std::string>& argv, const std::string& output_path) : output_path_(output_path) {
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(output_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
  }
  ~BackgroundProcess() { stop(); }
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  std::string output() const { return read_file(output_path_); }

  // The child's pid while it runs (-1 once it has been waited for): for the
  // test's own signals (kill -9, SIGTERM).
  pid_t pid() const { return pid_; }

  // Waits until `done(output)` holds; false after the timeout or when the
  // process ended first. The timeout is a deadline for a hung process, so
  // callers give generous ones: it costs time only when the test fails.
  bool wait_until(const std::function<bool(const std::string&)>& done, double timeout_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      if (done(output())) return true;
      if (exited()) return done(output());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return done(output());
  }

  // Waits until the output contains `text` (as wait_until).
  bool wait_for(const std::string& text, double timeout_s) {
    return wait_until([&](const std::string& out) { return out.find(text) != std::string::npos; }, timeout_s);
  }

  // SIGINT, then wait (SIGKILL after 30 s: a loaded machine may take seconds
  // to let a process close its logs). Returns the exit status, -1 if killed.
  int stop() {
    if (pid_ <= 0) return status_;
    if (!exited()) {
      kill(pid_, SIGINT);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
      while (!exited() && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      if (!exited()) {
        kill(pid_, SIGKILL);
        int st = 0;
        waitpid(pid_, &st, 0);
        status_ = -1;
      }
    }
    pid_ = -1;
    return status_;
  }

  // Waits for the process to end by itself.
  int wait() {
    if (pid_ <= 0) return status_;
    int st = 0;
    waitpid(pid_, &st, 0);
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    pid_ = -1;
    return status_;
  }

 private:
  bool exited() {
    if (pid_ <= 0) return true;
    int st = 0;
    const pid_t r = waitpid(pid_, &st, WNOHANG);
    if (r == pid_) {
      status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
      pid_ = -1;
      return true;
    }
    return false;
  }

  std::string output_path_;
  pid_t pid_ = -1;
  int status_ = -1;
};

}  // namespace rigctl::test
