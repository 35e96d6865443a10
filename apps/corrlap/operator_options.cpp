#include "operator_options.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <iostream>

namespace corrlap::cli {

void OperatorOptions::add_options(CLI::App& cmd) {
  source.add_options(cmd, /*with_mesh=*/true);
  std::string names;
  for (const auto& n : discretization_registry().names()) names += (names.empty() ? "" : ", ") + n;
  cmd.add_option("--method", method, "discretization: " + names)->required();
  normals.add_options(cmd);
  cmd.add_option("--lambda", lambda, "stabilization weight (polydec 1, interpolated 0.1)");
  cmd.add_option("--kappa", kappa, "interpolated: flat correction factor (2 = DGtal, 1 = paper)");
  cmd.add_option("--assembly", assembly, "interpolated: global (DGtal L0, default) | local")
      ->check(CLI::IsMember({"global", "local"}));
  cmd.add_option("--mass", mass, "fem: full (default) | lumped; heat-kernel: measure (default) | identity")
      ->check(CLI::IsMember({"full", "lumped", "measure", "identity"}));
  cmd.add_option("--t", heat_t, "heat-kernel: diffusion time (default 0.1 h^(2/3), docs/math.md §6)");
  cmd.add_option("--cutoff", cutoff, "heat-kernel: couple points closer than cutoff * sqrt(2t) (default 3)");
  cmd.add_option("--orientation", orientation,
                 "normals with u.n <= 0: clamp (default: raise u.n to 0.05) | warn (use as given; L, M may break their "
                 "contract) | error")
      ->check(CLI::IsMember({"error", "warn", "clamp"}));
  cmd.add_option("--param", params, "method parameter key=value (repeatable)");
  cmd.add_option("--config", config_file, "JSON object of method parameters");
  cmd.add_option("--threads", threads, "worker threads (default: all; env CORRLAP_THREADS)");
}

OperatorOptions::Input OperatorOptions::prepare(bool extras) const {
  if (threads > 0) set_thread_count(threads);
  const auto disc = make_discretization(method);
  Input in;
  LoadedSurface surface = source.load();
  // The one normal resolution of the library (docs/math.md §1.5): the same field for every command.
  in.normals = normals.resolve(surface, disc->required_normals(), method);
  in.mesh = std::move(surface.mesh);
  if (!config_file.empty()) in.params = Config::from_json_file(config_file);
  in.params.merge(Config::from_key_values(params));
  if (lambda) in.params.set("lambda", *lambda);
  if (kappa) in.params.set("kappa", *kappa);
  if (heat_t) in.params.set("t", *heat_t);
  if (cutoff) in.params.set("cutoff", *cutoff);
  if (!assembly.empty()) in.params.set("assembly", assembly);
  if (!mass.empty()) in.params.set("mass", mass);
  if (!orientation.empty()) in.params.set("orientation", orientation);
  if (extras) {
    bool supported = false;
    for (const auto& p : disc->parameters()) supported = supported || p.name == "extras";
    if (supported)
      in.params.set("extras", true);
    else
      std::cerr << "warning: " << method << " has no extra operators (D0, sharp, flat, M1)\n";
  }
  return in;
}

Operators OperatorOptions::assemble(const Input& in) const {
  Operators ops = make_discretization(method)->assemble(in.mesh, in.normals, in.params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  return ops;
}

Operators OperatorOptions::build(bool extras) const { return assemble(prepare(extras)); }

}  // namespace corrlap::cli
