// `rigctl road-target`: a target for rigctl iterate over an ISO 8608 road (tools/iterate/road_target_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/iterate/road_target_command.hpp"

namespace rigctl::cli {

namespace {

class RoadTargetSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("road-target", "A target for rigctl iterate: a quarter car's wheel displacement over an ISO 8608 road (docs/drive-iteration.md)");
    c->add_option("config", options_.config_path, "Quarter-car config: its wheel, body, tyre and mid-stroke")->required()->check(CLI::ExistingFile);
    c->add_option("--class", road_class_, "ISO 8608 road class A..E")->capture_default_str()->check(CLI::IsMember({"A", "B", "C", "D", "E"}));
    c->add_option("--speed", options_.spec.speed_m_s, "Road speed [m/s]")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--duration", options_.spec.duration_s, "Length [s]")->capture_default_str()->check(CLI::PositiveNumber);
    c->add_option("--seed", options_.spec.seed, "Seed of the road's random phases")->capture_default_str();
    c->add_option("--channel", options_.channel, "Column name of the wheel displacement")->capture_default_str();
    c->add_option("--out", options_.out_path, "Run file to write (CSV), or RPC III (.rsp, .tim)")->required();
    return *c;
  }

  int run(const Invocation& invocation) override {
    options_.spec.road_class = iso_road_class_from_letter(road_class_);
    run_road_target(options_, invocation.out);
    return 0;
  }

 private:
  RoadTargetOptions options_;
  std::string road_class_ = "C";
};

}  // namespace

std::unique_ptr<Subcommand> make_road_target_subcommand() { return std::make_unique<RoadTargetSubcommand>(); }

}  // namespace rigctl::cli
