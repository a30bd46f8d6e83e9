// `rigctl make-run`: a run file with hidden effects, for the diagnosis tests (tools/hidden_effects/make_run.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/hidden_effects/effect_texts.hpp"
#include "tools/hidden_effects/make_run.hpp"

namespace rigctl::cli {

namespace {

class MakeRunSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("make-run", "Hidden-effect generator: a run file from the simulated closed loop with chosen effects switched on (diagnosis tests)");
    c->add_option("--rig", rig_, "Rig kind: " + known_kind_names<RigKind>())->required();
    c->add_option("--config", options_.config_path, "Rig config (default: config/<rig>.yaml)");
    c->add_option("--case", options_.case_name, "Excitation case of the config (default: the rig's diagnosis case)");
    c->add_option("--effect", effect_texts_, "CAUSE[:weak|strong|LEVEL], repeatable; none or absent: a clean run");
    c->add_option("--duration", options_.duration_s, "Run length [s] (default: the profile's)");
    c->add_option("--seed", options_.seed, "Seed of the sensor noise, the parameter draw and (without --form) the form");
    c->add_option("--tolerance", options_.tolerance,
                  "Half-width of every plant parameter's draw, a fraction (default 0.05: +-5 %); 0: nominal plant, "
                  "nominal controller and demand");
    c->add_option("--form", options_.form, "Physical form of the effects, 0 or 1 (default: seed % 2)");
    c->add_option("--out", options_.out_csv, "Run file to write (CSV)")->required();
    c->add_option("--truth", options_.truth_json, "Write what was hidden (JSON)");
    return *c;
  }

  int run(const Invocation& invocation) override {
    options_.rig = parse_kind<RigKind>(rig_);
    options_.effects = parse_effect_texts(effect_texts_);
    make_run(options_, invocation.err);
    return 0;
  }

 private:
  MakeRunOptions options_;
  std::string rig_;
  std::vector<std::string> effect_texts_;
};

}  // namespace

std::unique_ptr<Subcommand> make_make_run_subcommand() { return std::make_unique<MakeRunSubcommand>(); }

}  // namespace rigctl::cli
