#pragma once
// Closest points on a triangle mesh: for every query point, the nearest point of the surface, the
// triangle it lies on and its barycentric coordinates there. The cotan comparison (paper §3.4,
// docs/math.md §10.6) maps values and normals from its reference mesh to the digital surface by this
// orthogonal projection plus linear interpolation.
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>
#include <vector>

namespace corrlap {

struct ClosestPoint {
  int triangle = -1;                                      ///< row of the mesh's triangles
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  ///< weights of the triangle's 3 corners (sum 1)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double distance = 0;
};

/// Exact nearest-point queries (no approximation) accelerated by a uniform grid of the triangles'
/// bounding boxes: the rings of cells around the query are searched until no unvisited cell can
/// hold a nearer triangle. Keeps its own copy of the mesh. Queries are const and thread-safe.
class TriangleLocator {
 public:
  /// V #V x 3, T #T x 3. Throws InputError for an empty mesh, an index out of range or a position
  /// that is not finite.
  TriangleLocator(const Eigen::MatrixX3d& V, const TriangleIndices& T);
  /// Throws InputError when p is not finite.
  ClosestPoint closest(const Eigen::Vector3d& p) const;
  const Eigen::MatrixX3d& vertices() const { return V_; }
  const TriangleIndices& triangles() const { return T_; }

 private:
  Eigen::MatrixX3d V_;
  TriangleIndices T_;
  Eigen::Vector3d origin_;
  double cell_ = 1;
  Eigen::Vector3i dims_;
  std::vector<int> cell_start_, cell_triangles_;  // CSR: triangles overlapping each cell
};

/// The closest point of every row of P (#P x 3), in parallel; result i belongs to row i.
std::vector<ClosestPoint> closest_points(const TriangleLocator& locator, const Eigen::MatrixX3d& P);

/// Nearest point of triangle (a, b, c) to p, with barycentric weights. Degenerate triangles (zero
/// area) are handled through their edges.
ClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

}  // namespace corrlap
