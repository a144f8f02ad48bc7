// gpucol-bench: benchmarks that measure gpucol beside its Bullet peers in one run and print tables
// (and CSV on request). Each subcommand lives in its own file and registers itself.
#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

#include "bench_commands.h"

namespace gpucol::bench {
std::vector<AddCommand>& registeredCommands() {
  static std::vector<AddCommand> commands;
  return commands;
}
}  // namespace gpucol::bench

int main(int argc, char** argv) {
  CLI::App app{"gpucol-bench: gpucol beside Bullet's own collision code, measured in one run"};
  app.require_subcommand(1);
  for (const auto& add : gpucol::bench::registeredCommands()) add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "gpucol-bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
