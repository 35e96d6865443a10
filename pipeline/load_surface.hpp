#pragma once
// Where a digital surface comes from, loaded one way for every front end: an implicit shape, a
// volume file, a volume in memory, a triangle mesh to voxelize, or a quad mesh of surfels
// (docs/architecture.md, "The data flow").
#include <Eigen/Core>
#include <array>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/io/voxel_values.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

namespace corrlap {

/// An implicit shape digitized on the grid h Z^3 (docs/math.md §1.2).
struct ImplicitShapeInput {
  std::string shape;  ///< a built-in name (named_shapes) or a polynomial in x, y, z ("x^2+y^2+z^2-1")
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  DigitizationParams digitization;
};

/// A volume file (every format of docs/io.md), its voxels inside by `inside` (default: every
/// nonzero value), centred at the origin. Anisotropic voxels are resampled to cubes of the finest
/// spacing first (load_surface; docs/io.md, "Physical coordinates").
struct VolumeFileInput {
  std::string path;
  InsideRule inside;
  std::optional<Eigen::Vector3i> raw_dimensions;  ///< required for .raw
  std::optional<double> h;                        ///< default: 2 / the longest side in voxels
};

/// A volume in memory, read where it is, in its own element type and layout (no copy): value
/// (x, y, z) at the bytes data + x * strides[0] + y * strides[1] + z * strides[2]. Any strides
/// work: C or Fortran order, views with steps, negative strides, and 0 along an axis (a broadcast
/// array, whose values repeat). Inside by `inside` (bool: true = 1); centred and resampled like a
/// volume file. The values are read during load_surface only; NaN is refused.
struct VolumeArrayInput {
  Eigen::Vector3i size = Eigen::Vector3i::Zero();
  const void* data = nullptr;
  VoxelValueType type = VoxelValueType::Float64;
  std::array<std::ptrdiff_t, 3> strides = {0, 0, 0};  ///< in bytes
  bool byte_swapped = false;                          ///< the values are in the other byte order
  InsideRule inside;
  VolumeGeometry geometry;  ///< voxel (x, y, z) -> physical coordinates (default: the identity)
  std::optional<double> h;  ///< default: 2 / the longest side in voxels

  /// A C-ordered array of doubles indexed [x][y][z]: value (x, y, z) at values[(x * size.y() + y)
  /// * size.z() + z]. InputError when the count does not match the size.
  static VolumeArrayInput c_order(std::span<const double> values, const Eigen::Vector3i& size);
};

/// A closed triangle (or polygon) mesh voxelized: the voxels whose centres are inside.
struct MeshFileInput {
  std::string path;         ///< .obj, .ply, .off
  int resolution = 0;       ///< longest bounding-box side = resolution voxels; or
  std::optional<double> h;  ///< the grid step in mesh units (exactly one of the two)
};

/// A quad mesh of surfels taken as it is (vertex and face order kept): no voxels, no shape.
struct QuadMeshInput {
  std::string path;  ///< a mesh file (.obj, .ply, .off) of quads; or, when empty,
  SurfelMesh mesh;   ///< the mesh itself (e.g. numpy V, F)
};

using SurfaceInput = std::variant<ImplicitShapeInput, VolumeFileInput, VolumeArrayInput, MeshFileInput, QuadMeshInput>;

/// The map from the input's voxel indices to the world coordinates of the mesh, world = h (index -
/// shift), and from them to physical coordinates. Index: a volume's voxel (i, j, k) (pointels at
/// half-integers; for anisotropic voxels, the voxel of the isotropic resampling), or the digital
/// point for the other inputs (shift 0). Physical: the volume's geometry applied to the index
/// (millimetres for medical formats, the index itself for a volume without geometry); the world
/// coordinates themselves for the other inputs (a shape's or a mesh file's own units).
class VoxelFrame {
 public:
  VoxelFrame() = default;
  VoxelFrame(double h, const Eigen::Vector3d& shift, std::optional<VolumeGeometry> geometry = std::nullopt)
      : h_(h), shift_(shift), geometry_(std::move(geometry)) {}
  /// World length of a voxel side (the grid step).
  double h() const { return h_; }
  /// The index of the world origin.
  const Eigen::Vector3d& shift() const { return shift_; }
  /// Positions (rows) in world units -> in voxel indices.
  Eigen::MatrixX3d to_index(const Eigen::MatrixX3d& world) const {
    return Eigen::MatrixX3d((world / h_).rowwise() + shift_.transpose());
  }
  Eigen::Vector3d to_world(const Eigen::Vector3d& index) const { return h_ * (index - shift_); }
  /// Lengths scale by 1 / h into index units, curvatures by h.
  double length_to_index(double length) const { return length / h_; }

  /// The volume's index -> physical map (isotropic voxels); none for the other inputs.
  const std::optional<VolumeGeometry>& geometry() const { return geometry_; }
  /// Positions (rows) in world units -> physical coordinates.
  Eigen::MatrixX3d to_physical(const Eigen::MatrixX3d& world) const;
  /// The physical length of a world length: h times the physical side of a voxel (1 without geometry).
  double length_to_physical(double length) const;
  /// Unit normals (rows) in world coordinates -> unit normals of the physical surface.
  Eigen::MatrixX3d normals_to_physical(const Eigen::MatrixX3d& normals) const;
  /// True when world -> physical reverses orientation (a direction matrix of determinant < 0):
  /// faces are then written in the other order, so that they keep facing outwards.
  bool mirrors() const;
  /// The anatomical space of the physical coordinates (Unknown without geometry).
  PhysicalSpace space() const { return geometry_ ? geometry_->space : PhysicalSpace::Unknown; }
  /// The map from physical coordinates into the anatomical space `to` (space_change): the identity
  /// for the frame's own space; InputError "space" saying why when the frame's space is unknown.
  Eigen::Matrix3d space_change_to(PhysicalSpace to) const;

 private:
  double h_ = 1.0;
  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero();
  std::optional<VolumeGeometry> geometry_;
};

/// The frame of a volume's voxels in the centred box of read_volume_as_voxels (or of their
/// resampling to cubes, isotropic_resampling.hpp), whose lower corner is `lower`: the box is the
/// voxels [0, size - 1] - shift padded by one, so shift = -lower - 1. `geometry` maps the voxel
/// index to physical coordinates. load_surface's frame of a volume, and the distributed front end's.
VoxelFrame volume_voxel_frame(const Eigen::Vector3i& lower, double h, const VolumeGeometry& geometry);

/// A digital surface with what it came from.
struct LoadedSurface {
  SurfelMesh mesh;
  std::optional<VoxelGrid> grid;       ///< the voxels (all inputs but quad meshes)
  std::optional<ImplicitShape> shape;  ///< implicit shapes only (true and exact normals)
  double h = 0.0;                      ///< grid step (a quad mesh: its mean edge length, SurfelMesh::grid_step)
  VoxelFrame frame;                    ///< voxel indices -> world coordinates -> physical coordinates
  int components = 0;                  ///< connected components of the surface (all kept)
  double anisotropy = 1.0;             ///< a volume's coarsest over finest voxel side (> 1: resampled to cubes)
  std::string description;             ///< provenance for logs and metrics ("sphere1, h=0.1")

  const ImplicitShape* shape_ptr() const { return shape ? &*shape : nullptr; }
  const VoxelGrid* grid_ptr() const { return grid ? &*grid : nullptr; }
};

/// What loading has to say besides the surface: warnings (a mesh to voxelize with holes,
/// non-manifold edges, self-intersections) and notes (the voxelization's size). The library prints
/// nothing; a front end shows them its way. Either may be empty.
struct LoadMessages {
  std::function<void(const std::string&)> warning;
  std::function<void(const std::string&)> note;
};

/// Loads the surface. Throws InputError naming the bad parameter (e.g. "h", "resolution",
/// "threshold": Error::parameter) or the file, IoError for unreadable files, and InputError when no
/// voxel is inside.
LoadedSurface load_surface(const SurfaceInput& input, const LoadMessages& messages = {});

/// At most this many distinct labels in volume_labels: more looks like a grey-level image.
inline constexpr std::size_t kMaxVolumeLabels = 65535;

/// The distinct nonzero values of a volume, ascending (the labels of a segmentation). InputError
/// tagged "labels" when there are more than kMaxVolumeLabels (a grey-level image: a threshold is
/// meant) or none; NaN values are refused.
std::vector<double> volume_labels(const VolumeData& volume);
/// volume_labels of the file (read whole, in its own type).
std::vector<double> volume_labels(const std::string& path);

/// A view of a volume read whole (read_volume_data) as an in-memory volume with its geometry, so
/// that several rules (one label each) digitize it without reading the file again. `volume` must
/// outlive the result.
VolumeArrayInput volume_array(const VolumeData& volume, const InsideRule& inside, std::optional<double> h = {});

/// Refuses (InputError tagged "h", `what` first) a grid step that is not positive and finite.
void check_grid_step(double h, const std::string& what);

/// Only the voxels of an input that has some (not a QuadMeshInput: InputError), without the surface.
VoxelGrid load_voxels(const SurfaceInput& input, const LoadMessages& messages = {});

/// The provenance string of an input ("sphere1, h=0.1", "\"x^2+y^2+z^2-1\", h=0.2",
/// "head.vol, threshold 0", "bunny.obj, resolution 128", "s.obj").
std::string describe(const SurfaceInput& input);

/// resolve_normals on a loaded surface (its shape and voxels).
inline NormalFields resolve_normals(const LoadedSurface& surface, NormalKind need, const NormalRequest& request,
                                    const std::string& what = "the method") {
  return resolve_normals(surface.mesh, need, request, surface.shape_ptr(), surface.grid_ptr(), what);
}

}  // namespace corrlap
