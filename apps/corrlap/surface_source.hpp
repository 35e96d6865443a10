#pragma once
// Shared CLI options that produce a digital surface: --shape/--polynomial/--volume/--mesh-file/--mesh,
// --h, --center, --bbox, --offset, --threshold, --raw-dimensions, --resolution. They are parsed
// into a SurfaceInput and loaded by the library's load_surface (pipeline/load_surface.hpp).
#include <CLI/CLI.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_checks.hpp>
#include <optional>
#include <string>
#include <vector>

namespace corrlap::cli {

/// --output-units: positions written in world units (default) or in the input's voxel units (the
/// volume file's voxel indices, pointels at half-integers; digital coordinates for other sources),
/// through the surface's VoxelFrame. Lengths scale by 1/h and curvatures by h with them.
struct OutputUnits {
  bool voxels = false;
  VoxelFrame frame;

  /// "world" or "voxels"; anything else is an InputError.
  static OutputUnits parse(const std::string& name, const LoadedSurface& surface);
  const char* name() const { return voxels ? "voxels" : "world"; }
  SurfelMesh mesh(const SurfelMesh& m) const;
  Eigen::VectorXd lengths(const Eigen::VectorXd& v) const { return voxels ? Eigen::VectorXd(v / frame.h()) : v; }
  Eigen::VectorXd curvatures(const Eigen::VectorXd& v) const { return voxels ? Eigen::VectorXd(v * frame.h()) : v; }
};

struct SurfaceSource {
  std::string shape, polynomial, volume, mesh;
  std::string mesh_file;  ///< closed triangle/polygon mesh voxelized (.obj, .ply, .off)
  int resolution = 0;     ///< mesh files: longest bbox side = resolution voxels
  double h = 1.0;
  std::vector<double> center = {0.0, 0.0, 0.0};
  std::vector<double> bbox = {-10.0, 10.0};
  int offset = 5;
  double threshold = 0.0;           ///< volumes: voxels with value > threshold are inside
  std::vector<int> raw_dimensions;  ///< raw volumes: NX NY NZ
  bool allow_mesh = true;
  CLI::Option* h_option = nullptr;  ///< to know whether --h was given explicitly

  /// Adds the options to a subcommand.
  void add_options(CLI::App& cmd, bool with_mesh = true);

  /// The parsed options as the library's description of the input; InputError for options that
  /// do not go together (--resolution without --mesh-file, --mesh-file without a step...).
  SurfaceInput input() const;
  /// load_surface(input()): warnings and notes go to stderr, library errors name the CLI flags.
  LoadedSurface load() const;
  /// Short description for logs ("sphere1, h=0.1").
  std::string describe() const;
};

/// Help of --allow-nonmanifold, which regularize, reconstruct and study still accept so that
/// existing command lines keep working.
inline constexpr const char* kAllowNonmanifoldNote =
    "accepted and ignored: surfaces from voxels are split into manifold sheets where voxels touch along an edge or "
    "at a corner (docs/math.md §1.4)";

/// The library's check_regularizable, its error naming `command`.
void check_regularizable(const SurfelMesh& mesh, const std::string& command);

}  // namespace corrlap::cli
