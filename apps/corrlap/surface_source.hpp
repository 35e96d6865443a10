#pragma once
// Shared CLI options that produce a digital surface: --shape/--polynomial/--volume/--mesh-file/--mesh,
// --h, --center, --bbox, --offset, --threshold, --raw-dimensions, --resolution. They are parsed
// into a SurfaceInput and loaded by the library's load_surface (pipeline/load_surface.hpp).
#include <CLI/CLI.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/io/voxel_values.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/pipeline/surface_checks.hpp>
#include <optional>
#include <string>
#include <vector>

namespace corrlap::cli {

/// --output-units: the coordinates of the meshes written, through the surface's VoxelFrame:
/// physical (default): a volume's physical coordinates (its file's geometry, millimetres for medical
///   formats; voxel indices for a volume without geometry), a shape's or mesh file's own units;
/// world: the normalized coordinates of the computation (a volume centred, its longest side spanning 2);
/// voxels: the voxel indices (pointels at half-integers; digital coordinates for other sources).
/// Lengths and curvatures (H, displacement) scale with the positions; normals follow them.
/// --output-space: the anatomical space of physical coordinates: the input file's own (default, so
/// that the outputs overlay the scan in the program that wrote it), or RAS or LPS, converted by
/// flipping axes (docs/io.md, "Anatomical spaces").
struct OutputUnits {
  enum class Kind { Physical, World, Voxels };
  Kind kind = Kind::Physical;
  VoxelFrame frame;
  /// Physical output: the space written, and the map from the input's space into it.
  PhysicalSpace space = PhysicalSpace::Unknown;
  Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();

  static constexpr const char* kDefault = "physical";
  static constexpr const char* kDefaultSpace = "file";
  static constexpr const char* kHelp =
      "coordinates of the outputs: physical (the volume file's physical coordinates, e.g. millimetres; "
      "voxel indices for a volume without geometry; a shape's or mesh file's own units), world (the normalized "
      "coordinates of the computation: volumes centred, the longest side spanning 2) or voxels (voxel indices, "
      "pointels at half-integers); lengths, curvatures and eigenvalues scale with them (docs/io.md)";
  static constexpr const char* kSpaceHelp =
      "anatomical space of physical outputs: file (the volume file's own: RAS for NIfTI, LPS for MetaImage, the "
      "'space' of an NRRD), ras or lps (x and y flipped from the file's space; an error when the file names no "
      "space)";
  /// `name`: "physical", "world" or "voxels"; `space`: "file", "ras" or "lps" (any case). InputError
  /// for anything else, and for ras/lps with other units than physical or an input in an unknown space.
  static OutputUnits parse(const std::string& name, const VoxelFrame& frame, const std::string& space = kDefaultSpace);
  static OutputUnits parse(const std::string& name, const LoadedSurface& surface,
                           const std::string& space = kDefaultSpace) {
    return parse(name, surface.frame, space);
  }
  const char* name() const;
  /// The space of the coordinates written: "RAS", "LPS", "LAS" or "unknown" for physical units, ""
  /// for world and voxel units (no anatomy).
  std::string space_name() const;
  /// The header comments of a mesh file that name its space ("SPACE=LPS", which 3D Slicer reads from
  /// OBJ and PLY files); none when the space is unknown.
  std::vector<std::string> comments() const;
  /// The header comment of a scalar file: what its values are and their units, e.g. "H: mean
  /// curvature in 1/length of physical units (SPACE=LPS)"; `power`: the values scale as
  /// length^-power (1 for curvatures, 2 for Gaussian curvatures and Laplacians).
  std::vector<std::string> scalar_comments(const std::string& what, int power) const;
  /// Positions (and h) in these units; faces reversed where the map mirrors, to keep facing outwards.
  SurfelMesh mesh(const SurfelMesh& m) const;
  /// Whether the map into these units mirrors (mesh() then reverses the faces).
  bool mirrors() const;
  /// One world length in these units.
  double length_scale() const;
  Eigen::VectorXd lengths(const Eigen::VectorXd& v) const { return v * length_scale(); }
  Eigen::VectorXd curvatures(const Eigen::VectorXd& v) const { return v / length_scale(); }
  /// Gaussian curvatures, eigenvalues of the Laplacian: 1 / length^2.
  Eigen::VectorXd inverse_areas(const Eigen::VectorXd& v) const { return v / (length_scale() * length_scale()); }
  /// Unit normals (rows) of the surface in these units.
  Eigen::MatrixX3d normals(const Eigen::MatrixX3d& n) const;
  /// Unit tangent directions (rows, e.g. principal directions) in these units.
  Eigen::MatrixX3d directions(const Eigen::MatrixX3d& d) const;
};

/// --output-units (and --output-space, for commands that write positions or vectors), the same
/// flags, help and defaults on every command.
struct OutputOptions {
  std::string units = OutputUnits::kDefault;
  std::string space = OutputUnits::kDefaultSpace;
  void add_options(CLI::App& cmd, bool with_space = true);
  OutputUnits parse(const LoadedSurface& surface) const { return OutputUnits::parse(units, surface, space); }
  OutputUnits parse(const VoxelFrame& frame) const { return OutputUnits::parse(units, frame, space); }
};

struct SurfaceSource {
  std::string shape, polynomial, volume, mesh;
  std::string mesh_file;  ///< closed triangle/polygon mesh voxelized (.obj, .ply, .off)
  int resolution = 0;     ///< mesh files: longest bbox side = resolution voxels
  double h = 1.0;
  std::vector<double> center = {0.0, 0.0, 0.0};
  std::vector<double> bbox = {-10.0, 10.0};
  int offset = 5;
  std::optional<double> threshold;  ///< volumes: voxels with value > threshold are inside
  std::optional<double> label;      ///< volumes: voxels with value == label are inside
  std::string labels;               ///< volumes: "all": one surface per distinct nonzero value
  CLI::Option* labels_option = nullptr;
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
  /// True for --labels all (commands that write one output per label handle it; the others refuse
  /// it through input()).
  bool all_labels() const { return labels == "all"; }
  /// The inside rule of --threshold / --label (default: every nonzero voxel).
  InsideRule inside() const;
};

/// Help of --allow-nonmanifold, which regularize, reconstruct and study still accept so that
/// existing command lines keep working.
inline constexpr const char* kAllowNonmanifoldNote =
    "accepted and ignored: surfaces from voxels are split into manifold sheets where voxels touch along an edge or "
    "at a corner (docs/math.md §1.4)";

/// The library's check_regularizable, its error naming `command`.
void check_regularizable(const SurfelMesh& mesh, const std::string& command);

}  // namespace corrlap::cli
