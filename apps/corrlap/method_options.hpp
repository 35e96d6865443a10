#pragma once
// The discretization and its parameters on the command line, derived from the methods' declared
// parameters (core/parameters.hpp): --method NAME, one flag per declared parameter name (--lambda,
// --mass, --clamp-min: the library name with "_" spelt "-"), --param key=value (repeatable) and
// --method-config FILE (a JSON object). Precedence: --method-config < --param < the flags.
// The same flags in every command that assembles operators (operators, eigs, solve, regularize,
// study), so a parameter is spelt one way everywhere.
#include <CLI/CLI.hpp>
#include <corrlap/core/config.hpp>
#include <map>
#include <string>
#include <vector>

namespace corrlap::cli {

/// Every declared parameter name of the registered methods, in first-declaration order, with the
/// help text of its flag (what it does, and per method its allowed values and default).
struct MethodFlag {
  std::string parameter;  ///< library name ("clamp_min")
  std::string flag;       ///< CLI spelling ("--clamp-min")
  std::string help;
  std::string type_name;  ///< what --help shows for the value: X (real), N (integer), a|b (choices)
  bool boolean = false;   ///< a flag without a value (sets true)
};
std::vector<MethodFlag> method_flags();

struct MethodOptions {
  std::string method;
  std::vector<std::string> params;  ///< --param key=value
  std::string config_file;          ///< --method-config
  std::map<std::string, std::string> flag_values;
  std::map<std::string, bool> flag_booleans;
  CLI::Option* method_option = nullptr;  ///< --method, to know whether it was given

  /// Adds the flags. `method_flag`: also --method (with `default_method` when not empty; required
  /// otherwise); commands that take a list of methods (study --methods) pass false.
  void add_options(CLI::App& cmd, bool method_flag = true, const std::string& default_method = {});

  /// The parameters given for `method` (this->method when empty). `only_declared`: drop the keys
  /// that method does not declare (a study applies one set of flags to several methods); otherwise
  /// unknown keys stay, and the method's ParameterList::read names them.
  Config config(const std::string& method = {}, bool only_declared = false) const;

  /// --param items and the flags as key=value items, for a library option that takes them (a
  /// study applies them to the methods that declare the key).
  std::vector<std::string> key_values() const;

  /// True when --method or any method parameter was given (--param, --method-config, a flag).
  bool any_given() const;
};

}  // namespace corrlap::cli
