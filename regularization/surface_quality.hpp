#pragma once
// How close a surface mesh is to the implicit shape it digitizes: the measures that
// `corrlap regularize` reports before and after (docs/regularization.md).
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/implicit_shape.hpp>

namespace corrlap {

struct SurfaceQuality {
  double distance_l1 = 0.0;           ///< mean distance of the vertices to {P = 0}
  double normal_angle_deg = 0.0;      ///< mean angle of the geometric vertex normals to the true ones
  double mean_curvature_error = 0.0;  ///< mean |H - H_true| of the corrected curvature on the surface
};

/// Area of the quad mesh: each face counts half the norm of the cross product of its diagonals
/// (its vector area; exact for planar quads).
double surface_area(const SurfelMesh& mesh);

/// Volume enclosed by the quad mesh (positive for outward faces, as the surfels are): the flux of x / 3
/// through each face split into two triangles, averaged over its two diagonals (exact for planar
/// quads, independent of the origin on a closed mesh).
double enclosed_volume(const SurfelMesh& mesh);

/// Geometric vertex normals of the mesh as it is (docs/math.md §1.5: normalized sums of the face
/// normals from the corners): what a viewer shades with.
Eigen::MatrixX3d geometric_vertex_normals(const SurfelMesh& mesh);

/// The measures for `mesh` against `shape`. The curvature is the corrected one (interpolated,
/// ball radius `curvature_radius`) with the mesh's own geometric normals, against the level set's
/// mean curvature at each vertex's projection.
SurfaceQuality measure_against_shape(const SurfelMesh& mesh, const ImplicitShape& shape, double curvature_radius);

}  // namespace corrlap
