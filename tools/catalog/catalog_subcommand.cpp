// `rigctl catalog add|repair|show|list|query`: the rig's run catalog
// (tools/catalog/catalog_command.hpp, docs/rig-health.md): one subcommand
// each, sharing --catalog and --config.
#include <CLI/CLI.hpp>

#include <utility>
#include <vector>

#include "tools/catalog/catalog_command.hpp"
#include "tools/cli/subcommand.hpp"

namespace rigctl::cli {

namespace {

class CatalogSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("catalog", "The rig's run catalog (SQLite): add, list, show, query, repair (docs/rig-health.md)");
    c->require_subcommand(1);
    auto* add = action(*c, "add", "Enter recorded runs (RUN.lcm or RUN.csv)", CatalogAction::kAdd);
    add->add_option("records", options_.records, "LCM logs or CSV run files")->required()->check(CLI::ExistingFile);
    auto* repair = action(*c, "repair", "Complete killed runs from their logs; enter the logs of --log-dir not in the catalog", CatalogAction::kRepair);
    for (auto* a : {add, repair}) {
      a->add_option("--rig-name", options_.rig_name, "The rig's name in the catalog (default: the config's, else the rig kind)");
      a->add_option("--channel-prefix", options_.channel_prefix, "Telemetry channel prefix of the logs")->capture_default_str();
    }
    repair->add_option("--log-dir", options_.log_dir, "Folder of the rig's run logs")->check(CLI::ExistingDirectory);
    action(*c, "show", "One run in full: fields, channel statistics, diagnoses", CatalogAction::kShow)
        ->add_option("id", options_.run_id, "Run id")->required();
    for (auto* a : {action(*c, "list", "Runs as a table, oldest first", CatalogAction::kList),
                    action(*c, "query", "Runs as JSON with their channel statistics", CatalogAction::kQuery)}) {
      a->add_option("--rig", options_.rig, "Rig name or kind");
      a->add_option("--since", options_.since, "Started at or after (UTC, e.g. 2026-11-01 or 2026-11-01T08:00)");
      a->add_option("--until", options_.until, "Started before (UTC)");
      a->add_option("--end-reason", options_.end_reason, "completed, faulted, interrupted, killed, running, unknown");
      a->add_option("--where", options_.where, "CHANNEL.STAT<VALUE or >VALUE (stat: min, max, mean, std, rms), e.g. x_r.max>0.05; repeatable");
    }
    return *c;
  }

  int run(const Invocation& invocation) override {
    for (const auto& [c, action] : actions_)
      if (c->parsed()) return run_catalog_command(action, options_, invocation.out, invocation.err);
    return 0;
  }

 private:
  // One action's subcommand with the options every action has.
  CLI::App* action(CLI::App& catalog, const char* name, const char* what, CatalogAction kind) {
    auto* c = catalog.add_subcommand(name, what);
    c->add_option("--catalog", options_.catalog_path, "Catalog file (default: the --config's catalog.path)");
    c->add_option("--config", options_.config_path, "Rig config: its catalog.path and catalog.rig_name")->check(CLI::ExistingFile);
    actions_.emplace_back(c, kind);
    return c;
  }

  CatalogCommandOptions options_;
  std::vector<std::pair<CLI::App*, CatalogAction>> actions_;
};

}  // namespace

std::unique_ptr<Subcommand> make_catalog_subcommand() { return std::make_unique<CatalogSubcommand>(); }

}  // namespace rigctl::cli
