#pragma once
// Digital surfaces as quad meshes: one quad per surfel, vertices = pointels (docs/math.md §1.3, §1.4).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "voxel_grid.hpp"

namespace corrlap {

/// Digital data of one surfel (docs/math.md §1.3): the pair of voxels (z, z + e_axis) it separates.
struct Surfel {
  Eigen::Vector3i lower_voxel;  ///< z; the other voxel is z + e_axis
  int axis = 0;                 ///< k, the axis orthogonal to the surfel
  int outward = 1;              ///< +1 if the trivial normal is +e_axis (z inside), -1 otherwise

  Eigen::Vector3i inner_voxel() const;
  Eigen::Vector3i outer_voxel() const;
  Eigen::Vector3d trivial_normal() const;
  /// Khalimsky coordinates 2c + 1 (odd on the tangent axes, even on `axis`).
  Eigen::Vector3i khalimsky() const;
  /// Positive in the reference's sense (docs/math.md §1.4): outward normal -e0, +e1 or -e2.
  bool positive() const;
};

/// A quad mesh of surfels. Faces are counter-clockwise seen from outside (docs/math.md §0):
/// ((x1-x0) x (x2-x1)) points along the outward normal.
struct SurfelMesh {
  Eigen::MatrixX3d positions;                                    ///< #V x 3, world units
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> faces;  ///< #F x 4 vertex ids
  std::vector<Surfel> surfels;  ///< #F when built from voxels, empty for meshes from files
  double h = 0.0;               ///< grid step (0 if unknown)

  int num_vertices() const { return int(positions.rows()); }
  int num_faces() const { return int(faces.rows()); }
  bool has_surfels() const { return !surfels.empty(); }

  /// Unit normal of each face from its corners: normalized sum over corners of
  /// (x_j - b) x (x_{j+1} - b), b = corner average (docs/math.md §1.5). Equals the trivial normal on surfels.
  Eigen::MatrixX3d face_normals_from_positions() const;
  /// Corner average of each face (#F x 3).
  Eigen::MatrixX3d face_centroids() const;
  /// Grid step if known, else the mean edge length.
  double grid_step() const;

  /// Throws InputError when ids are out of range, a face repeats a vertex, or positions are not finite.
  void validate(const char* what = "mesh") const;
};

}  // namespace corrlap
