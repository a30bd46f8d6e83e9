// Driver counters and events reach LCM and the run log.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <filesystem>

#include "rigctl/driver_status_t.hpp"
#include "rt/comms/telemetry_publisher.hpp"

using namespace rigctl;

TEST(DriverStatus, CountersAndEventsArePublishedAndLogged) {
  const auto log_path = std::filesystem::temp_directory_path() / ("rigctl_driver_status_" + std::to_string(::getpid()) + ".lcm");
  TelemetryMeta meta;
  meta.rig = "quarter_car";
  meta.layout.inputs = {{"x_r", "m"}};
  meta.layout.outputs = {{"u", "1"}};
  meta.setpoint_name = "x_ref";
  meta.controller_name = "pi";
  meta.term_names = {"p", "i"};
  int calls = 0;
  {
    TelemetryPublisher publisher(meta, "memq://", log_path.string(), 16);
    publisher.set_diagnostics_source(
        [&calls] {
          ++calls;
          DriverDiagnostics d;
          d.counters = {{"modbus_timeouts", 3}, {"modbus_reconnects", 1}};
          if (calls == 1) d.events = {"modbus 127.0.0.1:1502: timeout reading input registers 0-7 of unit 1"};
          return d;
        },
        "modbus");
    TelemetryRecord r;
    publisher.push(r);
    publisher.stop();
  }
  EXPECT_EQ(calls, 1) << "polled once at stop, not again by the destructor";
  lcm::LogFile log(log_path.string(), "r");
  int found = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "RIGCTL_DRIVER") continue;
    driver_status_t m;
    ASSERT_GE(m.decode(e->data, 0, e->datalen), 0);
    EXPECT_EQ(m.driver, "modbus");
    ASSERT_EQ(m.num_counters, 2);
    EXPECT_EQ(m.counter_names[0], "modbus_timeouts");
    EXPECT_EQ(m.counters[0], 3);
    ASSERT_EQ(m.num_events, 1);
    EXPECT_NE(m.events[0].find("input registers 0-7"), std::string::npos);
    ++found;
  }
  EXPECT_EQ(found, 1);
  std::filesystem::remove(log_path);
}
