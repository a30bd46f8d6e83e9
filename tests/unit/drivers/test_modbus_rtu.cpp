// Modbus RTU end to end: ModbusDaq on one end of a pseudo-terminal pair made
// by socat, SimModbusDaq on the other, both real libmodbus RTU. Skipped, with
// the reason, when socat is not installed.
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "drivers/modbus/modbus_daq.hpp"
#include "drivers/modbus/modbus_link.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "wait_until.hpp"

using namespace rigctl;
using rigctl::test::wait_until;

namespace {

std::string find_in_path(const std::string& program) {
  const char* path = getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string candidate = dirs.substr(start, end - start) + "/" + program;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

// A socat-made pseudo-terminal pair, linked at dir/client and dir/server.
// Only the socat this object started is ever signalled.
class PtyPair {
 public:
  explicit PtyPair(const std::string& socat) {
    char dir_template[] = "/tmp/rigctl_rtu_XXXXXX";
    if (mkdtemp(dir_template) == nullptr) return;
    dir_ = dir_template;
    client_ = dir_ + "/client";
    server_ = dir_ + "/server";
    const std::string log = dir_ + "/socat.log";
    pid_ = fork();
    if (pid_ == 0) {
      // socat reports on stderr (-d -d); keep it out of the test output.
      if (freopen(log.c_str(), "w", stderr) == nullptr) _exit(126);
      const std::string a = "pty,raw,echo=0,link=" + client_;
      const std::string b = "pty,raw,echo=0,link=" + server_;
      execl(socat.c_str(), "socat", "-d", "-d", a.c_str(), b.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    ready_ = pid_ > 0 && wait_until([&] {
      struct stat st {};
      return stat(client_.c_str(), &st) == 0 && stat(server_.c_str(), &st) == 0;
    });
  }
  ~PtyPair() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;

  bool ready() const { return ready_; }
  const std::string& client() const { return client_; }
  const std::string& server() const { return server_; }

 private:
  pid_t pid_ = -1;
  bool ready_ = false;
  std::string dir_, client_, server_;
};

ModbusChannel channel(const std::string& name, RegisterType type, int address, DataFormat format, WordOrder order,
                      Calibration cal, double safe = 0.0) {
  ModbusChannel c;
  c.name = name;
  c.unit = "1";
  c.point = {7, type, address, format, order};
  c.calibration = std::move(cal);
  c.safe = safe;
  return c;
}

ModbusDaqConfig rtu_config(const std::string& device) {
  ModbusDaqConfig c;
  c.connection.transport = ModbusTransport::kRtu;
  c.connection.device = device;
  c.connection.baud = 115200;
  c.connection.parity = 'E';
  c.connection.data_bits = 8;
  c.connection.stop_bits = 1;
  // A pty has no baud rate: the timeout is for a loaded machine, where the
  // slave's thread or socat may wait for a CPU (a reply missed by a timeout
  // is only retried, but a silent slave is the one test of a timeout here).
  c.connection.response_timeout_s = 0.2;
  c.connection.reconnect_interval_s = 0.1;
  c.poll_period_s = 0.005;
  c.max_sample_age_s = 0.5;
  using enum DataFormat;
  using enum WordOrder;
  constexpr auto kIn = RegisterType::kInputRegister;
  c.inputs = {
      channel("x_r", kIn, 0, kInt16, kHighFirst, LinearCalibration(6.1035e-6, 0.0)),
      channel("p1", kIn, 5, kFloat32, kLowFirst, TableCalibration(std::vector<double>{0, 1000, 2000},
                                                                  std::vector<double>{0.0, 1.0e7, 2.05e7})),
      channel("f_t", kIn, 7, kUint32, kHighFirst, LinearCalibration(0.01, -5000.0)),
  };
  c.outputs = {channel("u", RegisterType::kHoldingRegister, 0, kInt16, kHighFirst, LinearCalibration(3.0518e-5, 0.0))};
  return c;
}

class ModbusRtuTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string socat = find_in_path("socat");
    if (socat.empty()) GTEST_SKIP() << "socat is not installed (Debian package socat): no pseudo-terminal pair for RTU";
    pty_ = std::make_unique<PtyPair>(socat);
    ASSERT_TRUE(pty_->ready()) << "socat did not create the pseudo-terminal links";
    sim_ = std::make_unique<SimModbusDaq>(rtu_config(pty_->server()));
    sim_->start();
  }
  void TearDown() override {
    if (daq_) daq_->stop();
    if (sim_) sim_->stop();
  }

  Sample read() {
    Sample s;
    daq_->read_inputs(s, 0, ModbusDaq::now_ns());
    return s;
  }

  std::unique_ptr<PtyPair> pty_;
  std::unique_ptr<SimModbusDaq> sim_;
  std::unique_ptr<ModbusDaq> daq_;
};

TEST_F(ModbusRtuTest, ReadsInputsAndWritesAnOutput) {
  const double values[3] = {0.08, 1.525e7, 1234.56};
  sim_->set_inputs(values, 3);
  daq_ = std::make_unique<ModbusDaq>(rtu_config(pty_->client()));
  daq_->start(10.0);
  ASSERT_TRUE(wait_until([&] {
    const Sample s = read();
    return s.status == 0 && std::abs(s.value[0] - values[0]) < 3.1e-6 && std::abs(s.value[1] - values[1]) < 1.0 &&
           std::abs(s.value[2] - values[2]) < 0.005;
  })) << read().value[0] << " " << read().value[1] << " " << read().value[2];

  const double command = -0.3;
  daq_->write_outputs(&command, 1);
  double out = 0.0;
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(&out);
    return std::abs(out - command) < 1.6e-5;
  })) << out;

  // The server holds the value before it replies; the DAQ counts the write
  // once its I/O thread has the reply, which a loaded machine may run later.
  ASSERT_TRUE(wait_until([&] { return daq_->counters().writes > 0; })) << "the write's reply was never counted";
  const auto c = daq_->counters();
  EXPECT_TRUE(c.connected);
  EXPECT_GT(c.reads, 0);
  ASSERT_TRUE(wait_until([&] { return daq_->io_latency().count >= 200; }));
  const auto l = daq_->io_latency();
  std::cout << "I/O cycle (1 read + 1 write) RTU over a pty: " << l.count << " cycles, p50 " << l.p50_ns / 1000.0
            << " us, p99 " << l.p99_ns / 1000.0 << " us, max " << l.max_ns / 1000.0 << " us\n";
}

TEST_F(ModbusRtuTest, ExceptionsAndSilenceOnTheSerialLine) {
  daq_ = std::make_unique<ModbusDaq>(rtu_config(pty_->client()));
  daq_->start(10.0);
  sim_->add_exception({7, RegisterType::kInputRegister, 0, 0, 0x02});
  std::string events;
  const std::string expected = "modbus " + pty_->client() + ": exception 'Illegal data address' reading input registers 0-8 of unit 7";
  ASSERT_TRUE(wait_until([&] {
    for (const auto& e : daq_->diagnostics().events) events += e + "\n";
    return events.find(expected) != std::string::npos;
  })) << events;
  EXPECT_GT(daq_->counters().exceptions, 0);
  sim_->clear_exceptions();

  // A silent slave: timeouts, stale inputs; then back.
  sim_->set_silent(true);
  ASSERT_TRUE(wait_until([&] { return read().status == 0x7u; }));
  EXPECT_GT(daq_->counters().timeouts, 0);
  sim_->set_silent(false);
  ASSERT_TRUE(wait_until([&] { return read().status == 0u; }));
}

}  // namespace
