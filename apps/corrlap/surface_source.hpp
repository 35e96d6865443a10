#pragma once
// Shared CLI options that produce a digital surface: --shape/--polynomial/--volume/--mesh-file/--mesh,
// --h, --center, --bbox, --offset, --threshold, --raw-dimensions, --resolution.
#include <CLI/CLI.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <optional>
#include <string>
#include <vector>

namespace corrlap::cli {

/// A digital surface with what it came from: the voxels (shapes, volumes, mesh files) and the
/// implicit shape (--shape, --polynomial), needed by the II and true normals.
struct LoadedSurface {
  SurfelMesh mesh;
  std::optional<VoxelGrid> grid;
  std::optional<ImplicitShape> shape;
  /// Volumes are centred (docs/io.md): file voxel (x, y, z) is the digital point (x, y, z) - voxel_shift.
  Eigen::Vector3i voxel_shift = Eigen::Vector3i::Zero();
};

/// --output-units: positions written in world units (default) or in the input's voxel units (the
/// volume file's voxel indices, pointels at half-integers; digital coordinates for other sources):
/// p / h + voxel_shift. Lengths scale by 1/h and curvatures by h with them.
struct OutputUnits {
  bool voxels = false;
  double h = 1.0;
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();

  /// "world" or "voxels"; anything else is an InputError.
  static OutputUnits parse(const std::string& name, const LoadedSurface& surface);
  const char* name() const { return voxels ? "voxels" : "world"; }
  SurfelMesh mesh(const SurfelMesh& m) const;
  Eigen::VectorXd lengths(const Eigen::VectorXd& v) const { return voxels ? Eigen::VectorXd(v / h) : v; }
  Eigen::VectorXd curvatures(const Eigen::VectorXd& v) const { return voxels ? Eigen::VectorXd(v * h) : v; }
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

  /// The implicit shape when --shape/--polynomial is used.
  std::optional<ImplicitShape> implicit_shape() const;
  DigitizationParams digitization() const;
  /// Builds the voxel grid (shapes, volumes, mesh files); throws InputError when none was given.
  /// Mesh-file warnings (holes, non-manifold edges, self-intersections) go to stderr.
  VoxelGrid voxels() const;
  /// Builds the surface mesh from whichever source was given.
  SurfelMesh surface() const;
  /// The surface with its voxels and shape; InputError when the voxels are empty.
  LoadedSurface load() const;
  /// Short description for logs ("sphere1, h=0.1").
  std::string describe() const;
};

/// The surfaces `regularize` and `reconstruct` accept: closed (InputError naming the boundary
/// edges otherwise) and, unless `allow_nonmanifold`, manifold. Voxels that touch along an edge or at
/// a corner only pinch the surface: its normals and curvature are unreliable nearby and the solve
/// moves it by several voxels (measured), so that is refused by default, naming the counts.
void check_regularizable(const SurfelMesh& mesh, bool allow_nonmanifold, const std::string& command);

/// The boundary condition the solvers' problems get on this surface: none on a closed surface;
/// on an open one, natural (zero Neumann) conditions on its boundary edges, because every
/// discretization assembles L without boundary terms (docs/math.md §10.4).
struct BoundaryCondition {
  int boundary_edges = 0;
  bool closed() const { return boundary_edges == 0; }
  /// Empty when closed, else "the surface is open (N boundary edges): natural (zero Neumann)
  /// boundary conditions are used", for the user to read.
  std::string note() const;
  /// "closed" or "natural (zero Neumann) on N boundary edges", for JSON reports.
  std::string label() const;
};
BoundaryCondition boundary_condition(const SurfelMesh& mesh);

}  // namespace corrlap::cli
