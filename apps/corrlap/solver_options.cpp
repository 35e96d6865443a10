#include "solver_options.hpp"

#include <iostream>

namespace corrlap::cli {

void SolverOptions::add_options(CLI::App& cmd, const std::string& solver_help, bool positional_alias) {
  cmd.add_option("--solver", solver, solver_help)->group("solver");
  cmd.add_option("--solver-option", options,
                 "backend option key=value (repeatable; `corrlap backends` lists them), e.g. ordering=metis")
      ->group("solver");
  cmd.add_option("--solver-config", config_file,
                 "JSON object of backend options, e.g. {\"solver\": \"cg\", \"tolerance\": 1e-10}")
      ->group("solver");
  if (positional_alias)
    cmd.add_option("options", positional)->group("")->each([](const std::string& item) {
      std::cerr << "corrlap: note: the positional backend option '" << item << "' is deprecated; use --solver-option "
                << item << "\n";
    });
}

Config SolverOptions::config() const {
  Config c;
  if (!config_file.empty()) c = Config::from_json_file(config_file);
  c.merge(Config::from_key_values(positional));
  c.merge(Config::from_key_values(options));
  if (!solver.empty()) c.set("solver", solver);
  return c;
}

}  // namespace corrlap::cli
