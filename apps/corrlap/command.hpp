#pragma once
// Subcommands of the corrlap CLI register themselves here (one file per subcommand).
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace corrlap::cli {

struct Command {
  int order;  ///< position in --help
  std::string name;
  std::function<void(CLI::App& parent)> setup;  ///< adds the subcommand and its callback
};

std::vector<Command>& commands();

struct RegisterCommand {
  RegisterCommand(int order, std::string name, std::function<void(CLI::App&)> setup) {
    commands().push_back({order, std::move(name), std::move(setup)});
  }
};

}  // namespace corrlap::cli
