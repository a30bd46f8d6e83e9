// One subcommand of rigctl (`rigctl run`, `rigctl diagnose`, ...). Its folder
// defines it in a NAME_subcommand.cpp: the name, help and options in
// add_to(), the work in run(), and a factory make_NAME_subcommand().
// tools/CMakeLists.txt names it once (RIGCTL_SUBCOMMANDS, in the order
// `rigctl --help` lists them); tools/main.cpp adds every listed one and runs
// the one parsed. CLI11 is only forward-declared here: the headers of the
// jobs' libraries stay free of it.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace rigctl::cli {

// What a subcommand's run is handed besides its own options.
struct Invocation {
  std::string command_line;  // the program's arguments as typed, space-separated (bench records it)
  std::ostream& out;
  std::ostream& err;
};

class Subcommand {
 public:
  virtual ~Subcommand() = default;
  // Adds the subcommand, its help and its options to the program; the
  // options are read into the object's own members. Returns the subcommand.
  virtual CLI::App& add_to(CLI::App& program) = 0;
  // After a parse that chose this subcommand: the work; returns the exit
  // code. A ConfigError thrown out of it exits 2, any other exception 1
  // (tools/main.cpp).
  virtual int run(const Invocation& invocation) = 0;
};

// Every subcommand, in the order of RIGCTL_SUBCOMMANDS in tools/CMakeLists.txt
// (generated from it: tools/cli/subcommand_list.cpp.in).
std::vector<std::unique_ptr<Subcommand>> make_subcommands();

}  // namespace rigctl::cli
