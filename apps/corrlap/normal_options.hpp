#pragma once
// Options that choose normal fields, shared by operators, eigs, solve (and, through the same
// library function resolve_normals, curvature, normals and demo): --normals auto|true|ii|trivial,
// --face-normals FILE, --vertex-normals FILE, --ii-radius, --ii-alpha.
#include <CLI/CLI.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <string>

#include "surface_source.hpp"

namespace corrlap::cli {

/// Progress on stderr in steps of 10 % (II on fine grids runs for seconds to minutes).
ProgressFn stderr_progress(const std::string& what);

struct NormalOptions {
  std::string source = "auto";
  std::string face_file, vertex_file;
  IIParams ii;

  void add_options(CLI::App& cmd);
  NormalRequest request() const;
  /// resolve_normals for the surface (its shape and voxels); `what` names the consumer in errors.
  NormalFields resolve(const LoadedSurface& surface, NormalKind need, const std::string& what) const;
  /// The source actually used ("true", "ii", "trivial", "file").
  std::string describe(const LoadedSurface& surface) const;
};

}  // namespace corrlap::cli
