#pragma once
// Voxelization of a closed triangle (or polygon) mesh: every voxel whose centre h*z (docs/math.md §0)
// lies inside the mesh is set, so that real models become digital surfaces (extract_surface).
//
// Inside test: exact signed crossing counts of axis-parallel rays through the voxel centres
// (the winding number of the centre, computed row by row). Rays that hit an edge or a vertex
// are resolved by a symbolic perturbation of the ray (simulation of simplicity), with every
// edge test evaluated in a canonical vertex order, so that each ray crosses a watertight mesh
// exactly once per sheet: no double or missed crossings. For a closed mesh the result is the
// winding number (inside iff > 0 after orienting the mesh outward); for a mesh with holes the
// winding number depends on the ray, and the six axis rays vote (inside iff at least 4 say so).
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace corrlap {

struct MeshVoxelizationParams {
  /// Longest side of the mesh bounding box = `resolution` voxels (h = side / resolution).
  /// Used when > 0; otherwise `h` is the grid step.
  int resolution = 0;
  double h = 0.0;
};

/// What the voxelizer found about the input. Counts refer to the triangulated mesh after
/// merging vertices with identical positions.
struct MeshVoxelizationReport {
  int input_vertices = 0, merged_vertices = 0;  ///< vertices merged because they had equal positions
  int triangles = 0, degenerate_triangles = 0;  ///< degenerate: zero area
  int boundary_edges = 0;                       ///< edges with one triangle (holes)
  int nonmanifold_edges = 0;                    ///< edges with more than two triangles
  int inconsistent_edges = 0;                   ///< edges whose two triangles traverse them in the same direction
  bool inward_oriented = false;                 ///< negative signed volume: orientation flipped before the test
  std::int64_t ambiguous_voxels = 0;            ///< closed: winding number not in {0,1} (self-intersection,
                                                ///< overlapping parts); open: rays disagreeing
  std::int64_t self_intersections = 0;          ///< pairs of triangles without a common vertex whose
                                                ///< interiors cross (touching contacts are not counted)
  std::int64_t inside_voxels = 0;
  double h = 0.0;
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero(), bbox_max = Eigen::Vector3d::Zero();
  Eigen::Vector3i grid_size = Eigen::Vector3i::Zero();
  bool closed() const { return boundary_edges == 0 && nonmanifold_edges == 0; }
  /// Human-readable warnings (empty for a clean closed, consistently oriented mesh).
  std::vector<std::string> warnings() const;
};

/// Voxelizes `mesh` (faces of any degree, fanned into triangles). The grid box covers the mesh
/// bounding box plus one empty voxel on every side, so the digital surface is closed.
/// Throws InputError for an empty mesh, invalid ids, non-finite positions, invalid parameters
/// or when no voxel centre is inside (resolution too coarse). Parallel (TBB) over slabs; the
/// result does not depend on the thread count.
VoxelGrid voxelize_mesh(const PolygonMesh& mesh, const MeshVoxelizationParams& params,
                        MeshVoxelizationReport* report = nullptr);

}  // namespace corrlap
