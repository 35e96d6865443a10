#include "operator_options.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <iostream>

#include "deprecated.hpp"

namespace corrlap::cli {

void OperatorOptions::add_options(CLI::App& cmd) {
  source.add_options(cmd, /*with_mesh=*/true);
  method.add_options(cmd);
  normals.add_options(cmd);
  add_deprecated_alias(cmd, "--config", "--method-config", method.config_file);
  add_deprecated_alias(cmd, "--threads", "corrlap --threads N " + cmd.get_name(), threads);
}

OperatorOptions::Input OperatorOptions::prepare(bool extras) const {
  if (threads > 0) set_thread_count(threads);
  const auto disc = make_discretization(method.method);
  Input in;
  LoadedSurface surface = source.load();
  // The one normal resolution of the library (docs/math.md §1.5): the same field for every command.
  in.normals = normals.resolve(surface, disc->required_normals(), method.method);
  in.mesh = std::move(surface.mesh);
  in.frame = surface.frame;
  in.params = method.config();
  if (extras) {
    if (disc->parameters().find("extras"))
      in.params.set("extras", true);
    else
      std::cerr << "warning: " << method.method << " has no extra operators (D0, sharp, flat, M1)\n";
  }
  return in;
}

Operators OperatorOptions::assemble(const Input& in) const {
  Operators ops = make_discretization(method.method)->assemble(in.mesh, in.normals, in.params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  return ops;
}

Operators OperatorOptions::build(bool extras) const { return assemble(prepare(extras)); }

}  // namespace corrlap::cli
