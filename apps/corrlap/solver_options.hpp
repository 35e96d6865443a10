#pragma once
// The linear (and eigen) solver backend on the command line, one spelling in every command that
// solves: --solver NAME, --solver-option key=value (repeatable), --solver-config FILE (a JSON
// object of backend options). Precedence: --solver-config < --solver-option < --solver.
#include <CLI/CLI.hpp>
#include <corrlap/core/config.hpp>
#include <string>
#include <vector>

namespace corrlap::cli {

struct SolverOptions {
  std::string solver;
  std::vector<std::string> options;     ///< --solver-option key=value
  std::string config_file;              ///< --solver-config
  std::vector<std::string> positional;  ///< the deprecated positional key=value of solve and regularize

  /// `solver_help` describes --solver for this command. `positional_alias`: also accept the old
  /// positional key=value items (solve, regularize), with a deprecation note.
  void add_options(CLI::App& cmd, const std::string& solver_help, bool positional_alias = false);
  /// The backend configuration: file, then options, then "solver" from --solver when given.
  Config config() const;
};

}  // namespace corrlap::cli
