// I/O section, each path against the bare client a user would compare with:
// Modbus TCP (io_modbus.cpp), CAN over seqpacket (io_can.cpp) and LCM udpm
// (io_lcm.cpp); what they share is in io_support.hpp.
#include "tools/bench/io_support.hpp"
#include "tools/bench/sections.hpp"

namespace rigctl::bench {

Section io_section() {
  return {"io", "io: Modbus TCP and CAN round trips against bare clients, LCM udpm throughput and loss", [](Context& ctx) {
            Json j = Json::object();
            // As during a run (rt/realtime.cpp): no deep idle states, whose
            // exit latency would dominate every wake-up measured here.
            const DmaLatencyHold dma;
            j["cpu_dma_latency"] = dma.held() ? "held at 0 us" : "not held: " + dma.reason();
            ctx.out << "  cpu_dma_latency " << (dma.held() ? "held at 0 us" : "not held (" + dma.reason() + ")") << "\n";
            Table table({"path", "client", "p50 us", "p99 us", "p99.9 us", "max us", "count"});
            auto guarded = [&](const char* name, auto&& fn) {
              try {
                j[name] = fn();
              } catch (const std::exception& e) {
                Json err = Json::object();
                err["status"] = "error";
                err["error"] = std::string(e.what());
                j[name] = err;
                ctx.out << "  " << name << ": error: " << e.what() << "\n";
              }
              const Json* st = j[name].find("status");
              if (st != nullptr && st->string() == "skipped") {
                ctx.out << "  " << name << ": skipped: " << j[name].find("reason")->string() << "\n";
              }
            };
            guarded("modbus_tcp", [&] { return io::modbus_bench(ctx, table); });
            guarded("can_seqpacket", [&] { return io::can_bench(ctx, table); });
            ctx.out << table.text();
            Table lcm_table({"lcm udpm", "sub queue", "records", "pushed/s", "published/s", "lost", "loss"});
            guarded("lcm_udpm", [&] { return io::lcm_bench(ctx, lcm_table); });
            ctx.out << lcm_table.text();
            return j;
          }};
}

}  // namespace rigctl::bench
