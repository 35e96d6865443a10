#pragma once
// Options that choose normal fields, shared by every command that needs normals (operators, eigs,
// solve, regularize, curvature, normals): --normals auto|true|ii|trivial|convolved,
// --face-normals FILE, --vertex-normals FILE, --ii-radius, --ii-alpha. They build the library's
// NormalRequest, resolved by resolve_normals (estimators/normal_resolution.hpp).
#include <CLI/CLI.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <optional>
#include <string>

#include "surface_source.hpp"

namespace corrlap::cli {

/// Progress on stderr in steps of 10 % (II on fine grids runs for seconds to minutes).
ProgressFn stderr_progress(const std::string& what);

struct NormalOptions {
  std::string source = "auto";
  std::string face_file, vertex_file;
  std::optional<double> ii_k, ii_alpha;  ///< --ii-radius, --ii-alpha; unset: default_ii_params
  std::string ii_thin_parts;             ///< --ii-thin-parts: shrink | keep; empty: default_ii_params
  CLI::Option* source_option = nullptr;  ///< to know whether --normals was given explicitly

  void add_options(CLI::App& cmd);
  /// The request for this surface (its kind decides the II defaults).
  NormalRequest request(const LoadedSurface& surface) const { return request(surface.shape_ptr() != nullptr); }
  /// The same before the surface is loaded (the distributed front end): `implicit_shape` decides.
  NormalRequest request(bool implicit_shape) const;
  /// resolve_normals for the surface (its shape and voxels); `what` names the consumer in errors,
  /// which name the CLI flags.
  NormalFields resolve(const LoadedSurface& surface, NormalKind need, const std::string& what) const;
  /// The source actually used ("true", "ii", "trivial", "convolved", "file").
  std::string describe(const LoadedSurface& surface) const;
};

}  // namespace corrlap::cli
