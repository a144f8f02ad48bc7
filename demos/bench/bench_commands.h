#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <vector>

namespace gpucol::bench {

/// Adds one subcommand (and its callback) to the benchmark's command line.
using AddCommand = std::function<void(CLI::App&)>;

/// Every subcommand registered so far, in registration order.
std::vector<AddCommand>& registeredCommands();

/// A file that defines a subcommand registers it with one static object of this type, so that each
/// benchmark lives in its own file and main() needs no list of them.
struct CommandRegistration {
  /// Registers `add` to be called by main() before parsing.
  explicit CommandRegistration(AddCommand add) { registeredCommands().push_back(std::move(add)); }
};

}  // namespace gpucol::bench
