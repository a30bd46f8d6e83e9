// `rigctl bench --quick --json OUT` runs and writes every section it
// promises. CI only checks that the bench works: no timing thresholds here
// (these numbers depend on the machine and on what else it is doing).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "process.hpp"
#include "read_file.hpp"
#include "tools/bench/bench_command.hpp"
#include "tools/bench/json.hpp"
#include "tools/bench/support.hpp"

using rigctl::Json;
using rigctl::test::run_command;
namespace fs = std::filesystem;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfigDir = std::string(RIGCTL_SOURCE_DIR) + "/config";

using rigctl::test::read_file;

const Json& member(const Json& j, const std::string& key) {
  const Json* m = j.find(key);
  if (m == nullptr) throw std::runtime_error("missing key '" + key + "'");
  return *m;
}

// "ok" or "skipped" (with a reason); never "error".
void expect_ran(const Json& part, const std::string& what) {
  ASSERT_TRUE(part.contains("status")) << what;
  const std::string status = member(part, "status").string();
  if (status == "skipped") {
    EXPECT_FALSE(member(part, "reason").string().empty()) << what;
    std::printf("%s skipped: %s\n", what.c_str(), member(part, "reason").string().c_str());
    return;
  }
  EXPECT_EQ(status, "ok") << what << ": " << (part.contains("error") ? member(part, "error").string() : "");
}

bool finite_number(const Json& j) { return j.is_number() && std::isfinite(j.number()); }

void expect_latency(const Json& l, const std::string& what) {
  for (const char* k : {"count", "p50_us", "p99_us", "p999_us", "max_us"}) {
    ASSERT_TRUE(l.contains(k)) << what << " lacks " << k;
    EXPECT_TRUE(finite_number(member(l, k))) << what << "." << k;
  }
  EXPECT_GT(member(l, "count").number(), 0) << what;
  EXPECT_LE(member(l, "p50_us").number(), member(l, "max_us").number()) << what;
}

}  // namespace

TEST(BenchJson, RoundTrips) {
  Json j = Json::object();
  j["a"] = 1.5;
  j["b"] = "text \"quoted\"\n";
  j["c"] = Json::array();
  j["c"].push_back(1);
  j["c"].push_back(Json());
  j["d"]["e"] = true;
  j["nan"] = std::nan("");
  const Json back = Json::parse(j.dump());
  EXPECT_EQ(member(back, "a").number(), 1.5);
  EXPECT_EQ(member(back, "b").string(), "text \"quoted\"\n");
  EXPECT_EQ(member(back, "c").size(), 2u);
  EXPECT_TRUE(member(member(back, "d"), "e").boolean());
  EXPECT_TRUE(member(back, "nan").is_null());
  EXPECT_EQ(back.members().front().first, "a");  // insertion order kept
  EXPECT_THROW(Json::parse("{\"a\": }"), std::runtime_error);
}

TEST(BenchSupport, PercentilesOfAMicrosecondHistogramFollowTheLoopsConvention) {
  // 100 samples: 50 in [10, 11) us, 49 in [20, 21) us, one overflow at 900 us.
  std::vector<int64_t> counts(30, 0);
  counts[10] = 50;
  counts[20] = 49;
  const auto s = rigctl::bench::summary_from_us_histogram(counts, 1, 10, 900, 20.0);
  EXPECT_EQ(s.count, 100);
  EXPECT_EQ(s.p50_ns, 11'000);   // upper edge of the bin
  EXPECT_EQ(s.p99_ns, 21'000);
  EXPECT_EQ(s.p999_ns, 900'000);  // in the overflow: the max
  EXPECT_EQ(s.max_ns, 900'000);
}

TEST(BenchCommand, QuickRunWritesEverySection) {
  const fs::path dir = fs::temp_directory_path() / ("rigctl_bench_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string json_path = (dir / "bench.json").string();
  const auto r = run_command(kRigctl + " bench --quick --json " + json_path + " --config-dir " + kConfigDir);
  std::printf("%s\n", r.output.c_str());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json doc = Json::parse(read_file(json_path));
  fs::remove_all(dir);

  EXPECT_TRUE(member(doc, "quick").boolean());
  EXPECT_NE(member(doc, "command").string().find("bench --quick"), std::string::npos);
  const Json& machine = member(doc, "machine");
  for (const char* k : {"nproc", "cpu_model", "kernel"}) EXPECT_TRUE(machine.contains(k)) << k;

  const Json& sections = member(doc, "sections");
  std::vector<std::string> names;
  for (const auto& [name, value] : sections.members()) names.push_back(name);
  EXPECT_EQ(names, rigctl::bench_section_names());

  // Timing: the loop always runs; cyclictest may be missing (skipped, with
  // the reason). --quick makes one repetition per condition, each with the
  // steps of its slowest tick.
  const Json& timing = member(sections, "timing");
  expect_ran(timing, "timing");
  for (const char* condition : {"idle", "load"}) {
    const Json& c = member(timing, condition);
    const Json& runs = member(c, "runs");
    ASSERT_EQ(runs.size(), 1u) << condition;
    for (const Json& run : runs.items()) {
      const Json& loop = member(run, "rigctl");
      expect_latency(member(loop, "wakeup_latency"), std::string(condition) + " loop wake-up");
      expect_latency(member(loop, "compute"), std::string(condition) + " loop compute");
      EXPECT_TRUE(member(loop, "compute_fraction_of_period").contains("p99"));
      EXPECT_TRUE(member(member(loop, "stages"), "max_us").contains("hand_off"));
      const Json& ct = member(run, "cyclictest");
      expect_ran(ct, std::string(condition) + " cyclictest");
      if (member(ct, "status").string() == "ok") {
        expect_latency(member(ct, "wakeup_latency"), std::string(condition) + " cyclictest");
        EXPECT_TRUE(member(member(c, "ratio_rigctl_over_cyclictest"), "p99").contains("median"));
      }
    }
    EXPECT_TRUE(member(c, "compute_max_us").contains("median"));
    EXPECT_GE(member(member(c, "slowest_tick_of_all_runs"), "slowest_tick").number(), 0);
  }

  // Plant: every case, its reference, the fixed-step sweep with errors, and
  // the reference's right-hand side agreeing with the plant's.
  const Json& plant = member(sections, "plant");
  expect_ran(plant, "plant");
  const Json& cases = member(plant, "cases");
  for (const char* name : {"quarter_car", "pneumatic_rotary", "half_car_bump", "half_car_iso_c"}) {
    ASSERT_TRUE(cases.contains(name)) << name;
    const Json& c = member(cases, name);
    EXPECT_GT(member(member(c, "reference"), "steps").number(), 0) << name;
    EXPECT_TRUE(finite_number(member(member(c, "reference"), "real_time_factor"))) << name;
    const Json& fixed = member(c, "fixed_step");
    ASSERT_GE(fixed.size(), 3u) << name;
    bool has_default = false;
    for (const Json& f : fixed.items()) {
      EXPECT_TRUE(finite_number(member(f, "real_time_factor"))) << name;
      has_default = has_default || member(f, "substeps").number() == member(c, "default_substeps").number();
      if (member(f, "substeps").number() == member(c, "default_substeps").number()) {
        // At the loop's own step the plant's output tracks the reference closely.
        const Json& out = member(member(member(f, "error"), "components"), member(c, "output").string());
        EXPECT_LT(member(out, "max_abs_over_range").number(), 1e-3) << name;
      }
    }
    EXPECT_TRUE(has_default) << name;
    const Json& agreement = member(c, "rhs_agreement");
    EXPECT_GT(member(agreement, "states_checked").number(), 0) << name;
    EXPECT_LT(member(agreement, "max_relative_difference").number(), 1e-6)
        << name << ": the reference's equations differ from the plant's (tools/bench/reference.cpp)";
  }

  // I/O: Modbus and CAN always run here (loopback, socketpair); LCM udpm
  // needs root for its network namespace.
  const Json& io = member(sections, "io");
  expect_ran(io, "io");
  const Json& modbus = member(io, "modbus_tcp");
  expect_ran(modbus, "modbus");
  const Json& same = member(modbus, "same_cpu");  // also cross_cpu on a machine with two CPUs or more
  expect_latency(member(member(same, "driver"), "cycle_time"), "modbus driver");
  expect_latency(member(member(same, "bare_libmodbus"), "cycle_time"), "bare libmodbus");
  EXPECT_TRUE(same.contains("ratio_driver_over_bare"));
  const Json& can = member(io, "can_seqpacket");
  expect_ran(can, "can");
  const Json& can_same = member(can, "same_cpu");
  expect_latency(member(member(can_same, "can_transport"), "round_trip"), "can transport");
  expect_latency(member(member(can_same, "bare_socketpair"), "round_trip"), "bare socketpair");
  const Json& lcm = member(io, "lcm_udpm");
  expect_ran(lcm, "lcm");
  if (member(lcm, "status").string() == "ok") {
    for (const char* run : {"400Hz", "10kHz"}) {
      const Json& r = member(member(lcm, "runs"), run);
      expect_ran(r, std::string("lcm ") + run);
      EXPECT_GT(member(r, "received").number(), 0) << run;
    }
  }

  // Diagnosis: a placeholder until rigctl diagnose is measured.
  const Json& diagnosis = member(sections, "diagnosis");
  EXPECT_TRUE(diagnosis.contains("status"));

  // Diagnosis sweep (quick: two quarter-car runs, two at a time): each
  // run's diagnosis time is part of its whole time (making the run too).
  const Json& sweep = member(member(sections, "diagnosis_sweep"), "quarter_car");
  EXPECT_EQ(member(sweep, "jobs").number(), 2);
  ASSERT_EQ(member(sweep, "runs").size(), 2u);
  for (const Json& run : member(sweep, "runs").items()) {
    EXPECT_GT(member(run, "diagnose_seconds").number(), 0.0);
    EXPECT_LT(member(run, "diagnose_seconds").number(), member(run, "seconds").number());
  }

  // Scaling: plant cost against sub-steps and tick time against actuators.
  const Json& scaling = member(sections, "scaling");
  expect_ran(scaling, "scaling");
  EXPECT_GE(member(scaling, "plant_advance").size(), 10u);
  const Json& tick = member(scaling, "tick");
  for (const char* n : {"tick/actuators:1", "tick/actuators:2", "tick/actuators:4", "tick/actuators:8"}) {
    ASSERT_TRUE(tick.contains(n)) << n;
    EXPECT_GT(member(member(tick, n), "ns_per_tick").number(), 0) << n;
  }

  // Foxglove: three clients got every channel's messages through the
  // server, each matched to the moment the publisher handed it on; both
  // runs of the loop were measured (no timing thresholds here).
  const Json& foxglove = member(sections, "foxglove");
  expect_ran(foxglove, "foxglove");
  EXPECT_GT(member(foxglove, "messages_received").number(), 0);
  EXPECT_EQ(member(foxglove, "messages_unmatched").number(), 0);
  EXPECT_EQ(member(member(foxglove, "end_to_end_latency"), "count").number(), member(foxglove, "messages_received").number());
  for (const char* run : {"without_clients", "with_clients"}) {
    EXPECT_GT(member(member(member(foxglove, run), "wakeup_latency"), "count").number(), 0) << run;
  }
}

TEST(BenchCommand, UnknownSectionIsRejected) {
  const auto r = run_command(kRigctl + " bench --quick --section nonsense --config-dir " + kConfigDir);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("nonsense"), std::string::npos) << r.output;
}
