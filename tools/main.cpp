// rigctl: one program, one subcommand per job. Each job's folder defines its
// subcommands (tools/cli/subcommand.hpp) and tools/CMakeLists.txt lists them;
// this file only collects them, parses the command line and turns what
// escapes a subcommand into an exit code.
#include <CLI/CLI.hpp>

#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "config/config_reader.hpp"
#include "generated/rigctl_version.hpp"  // cmake/version.cmake: the version
#include "tools/cli/subcommand.hpp"
#include "tools/common/revision.hpp"

namespace {

std::string command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i > 0 ? " " : "") + std::string(argv[i]);
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rigctl: real-time controller and simulator for servo-hydraulic and pneumatic test rigs"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("rigctl ") + RIGCTL_VERSION + " (git " + rigctl::rigctl_revision() + ")");

  const auto subcommands = rigctl::cli::make_subcommands();
  std::vector<std::pair<CLI::App*, rigctl::cli::Subcommand*>> added;
  for (const auto& s : subcommands) added.emplace_back(&s->add_to(app), s.get());

  CLI11_PARSE(app, argc, argv);

  try {
    for (const auto& [parsed, subcommand] : added) {
      if (parsed->parsed()) return subcommand->run({command_line(argc, argv), std::cout, std::cerr});
    }
  } catch (const rigctl::ConfigError& e) {
    std::cerr << "rigctl: config error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rigctl: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
