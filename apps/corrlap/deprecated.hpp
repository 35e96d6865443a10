#pragma once
// Old option spellings kept while users move to the one CLI vocabulary (docs/cli.md): hidden from
// --help, same effect as the new flag, one line on stderr when used.
#include <CLI/CLI.hpp>
#include <iostream>
#include <string>

namespace corrlap::cli {

/// `old_flag` (e.g. "--estimator") writes into `target`, like `new_flag` (e.g. "--normals") does.
template <class T>
CLI::Option* add_deprecated_alias(CLI::App& cmd, const std::string& old_flag, const std::string& new_flag, T& target) {
  CLI::Option* o = cmd.add_option(old_flag, target)->group("");  // group "": not listed in --help
  o->each([old_flag, new_flag](const std::string&) {
    std::cerr << "corrlap: note: " << old_flag << " is deprecated; use " << new_flag << "\n";
  });
  return o;
}

/// The CLI spelling of a library parameter name: "ii_radius" -> "--ii-radius".
inline std::string flag_of(const std::string& parameter) {
  std::string flag = "--" + parameter;
  for (char& c : flag)
    if (c == '_') c = '-';
  return flag;
}

}  // namespace corrlap::cli
