#pragma once
// Options shared by `corrlap operators` and `corrlap eigs`: surface source, method and its
// parameters (method_options.hpp), normals; builds the operators and reports warnings on stderr.
#include <CLI/CLI.hpp>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/error.hpp>
#include <optional>
#include <string>
#include <vector>

#include "method_options.hpp"
#include "normal_options.hpp"
#include "surface_source.hpp"

namespace corrlap::cli {

struct OperatorOptions {
  SurfaceSource source;
  MethodOptions method;
  NormalOptions normals;
  int threads = 0;  ///< the deprecated per-command --threads (the global one is `corrlap --threads N`)

  void add_options(CLI::App& cmd);

  /// Mesh, normals and parameters ready for the discretization.
  struct Input {
    SurfelMesh mesh;
    NormalFields normals;
    Config params;
    VoxelFrame frame;  ///< the surface's world -> physical map (OutputUnits)
  };
  /// `extras`: also request D0/sharp/flat/M1/M_lumped when the method supports it.
  Input prepare(bool extras = false) const;
  /// Assembles the operators of a prepared input; warnings go to stderr.
  Operators assemble(const Input& in) const;
  /// prepare() then assemble().
  Operators build(bool extras = false) const;
};

/// Runs `solve()` (a linear or eigen solve of `ops`). A solver failure (NumericalError) on operators
/// that were assembled at a contract risk (Operators::contract_risk, e.g. orientation=warn) is
/// rethrown naming that likely cause and the remedy, instead of a bare "not positive definite".
template <class Solve>
auto explain_solver_failure(const Operators& ops, Solve&& solve) -> decltype(solve()) {
  try {
    return solve();
  } catch (const NumericalError& e) {
    if (ops.contract_risk.empty()) throw;
    throw NumericalError(std::string(e.what()) + "\n  likely cause: " + ops.contract_risk +
                         ", so L need not be negative semi-definite nor M positive definite\n  remedy: "
                         "--orientation clamp (the default) repairs those normals");
  }
}

}  // namespace corrlap::cli
