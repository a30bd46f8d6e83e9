// The CAN frame transport: one struct can_frame per SOCK_SEQPACKET record
// (socketpair and socket path), a full buffer that drops instead of
// blocking, records of the wrong size, and the SocketCAN error path (this
// kernel has no CAN, so nothing here touches a CAN_RAW socket beyond its
// failure).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <string>

#include "canopen_pair.hpp"
#include "drivers/canopen/can_transport.hpp"
#include "drivers/canopen/socketcan.hpp"

using namespace rigctl;
using namespace rigctl::test;
using canopen::CanFrame;
using canopen::make_frame;

TEST(CanTransport, SocketpairKeepsOneFramePerRecordAndSeesHangUp) {
  auto [a, b] = socketpair_seqpacket();
  const CanFrame f1 = make_frame(0x181, {1, 2, 3});
  const CanFrame f2 = make_frame(0x701, {5});
  ASSERT_TRUE(b.send(f1));
  ASSERT_TRUE(b.send(f2));
  CanFrame got;
  ASSERT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.can_id, 0x181U);
  EXPECT_EQ(got.len, 3);
  EXPECT_EQ(got.data[2], 3);
  ASSERT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.can_id, 0x701U);
  EXPECT_EQ(a.receive(got, 10), CanTransport::Rx::kTimeout);
  EXPECT_EQ(a.counters().rx, 2U);

  b.close();
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kHangUp);
  EXPECT_FALSE(a.send(f1));  // EPIPE, and no SIGPIPE killing the test
  EXPECT_EQ(a.counters().tx_errors, 1U);
}

TEST(CanTransport, FullBufferDropsTheFrameInsteadOfBlocking) {
  auto [a, b] = socketpair_seqpacket();
  int sent = 0;
  bool dropped = false;
  for (int i = 0; i < 1'000'000 && !dropped; ++i) {
    if (a.send(make_frame(0x201, {0, 0, 0, 0}))) {
      ++sent;
    } else {
      dropped = true;
    }
  }
  EXPECT_TRUE(dropped) << "never full after " << sent << " frames";
  EXPECT_GT(sent, 0);
  EXPECT_EQ(a.counters().tx_dropped, 1U);
  EXPECT_EQ(a.counters().tx_errors, 0U);
}

TEST(CanTransport, RecordOfTheWrongSizeIsCountedAndDropped) {
  auto [a, b] = socketpair_seqpacket();
  const unsigned char five[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(b.fd(), five, sizeof five, 0), 5);
  ASSERT_TRUE(b.send(make_frame(0x701, {5})));
  CanFrame got;
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kBadSize);
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(a.counters().rx_bad_size, 1U);
  EXPECT_EQ(a.counters().rx, 1U);
}

TEST(CanTransport, ListenerAcceptsAndConnectNamesAMissingPath) {
  TempDir dir;
  SeqpacketListener listener = listen_seqpacket(dir.socket());
  CanTransport client = connect_seqpacket(dir.socket());
  auto server = listener.accept(5000);
  ASSERT_TRUE(server.has_value());
  ASSERT_TRUE(client.send(make_frame(0x000, {1, 1})));
  CanFrame got;
  ASSERT_EQ(server->receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.len, 2);

  try {
    connect_seqpacket(dir.path + "/nobody.sock");
    FAIL() << "connect to a missing socket succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nobody.sock"), std::string::npos) << e.what();
  }
}

TEST(SocketCan, OpenFailsCleanlyNamingTheInterface) {
  const int probe = ::socket(PF_CAN, SOCK_RAW, 1 /* CAN_RAW */);
  const int probe_errno = errno;
  if (probe >= 0) ::close(probe);
  const uint32_t ids[] = {0x181, 0x081, 0x581, 0x701};
  try {
    CanTransport t = open_socketcan("can0", ids);
    GTEST_SKIP() << "this machine has a working can0; only the failure path is tested here";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'can0'"), std::string::npos) << msg;
    if (probe < 0 && probe_errno == EAFNOSUPPORT) {
      EXPECT_NE(msg.find("AF_CAN"), std::string::npos) << msg;
    }
  }
}

TEST(SocketCan, ValveConfiguredForCan0FailsToStartNamingIt) {
  CanopenValveConfig c = client_config();
  c.interface = "can0";
  CanopenValve valve(c);
  try {
    valve.start();
    GTEST_SKIP() << "a valve answered on can0";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("can0"), std::string::npos) << msg;
    EXPECT_NE(msg.find("node 1"), std::string::npos) << msg;
  }
  EXPECT_FALSE(valve.running());
}

// ---------------------------------------------------------------- start-up

