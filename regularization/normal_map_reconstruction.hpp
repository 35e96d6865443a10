#pragma once
// Reconstruction from a normal map (paper §4.2, Fig. 16): a fine triangle mesh plays the normal
// map of a coarse voxelization of itself. The surfels are subdivided, the fine mesh's normals are
// sampled at the subdivided surface by closest-point projection, and the regularization of paper
// §4.1 recovers the geometry from those normals. `corrlap reconstruct` runs it.
#include <Eigen/Core>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/closest_point.hpp>

namespace corrlap {

/// The default curvature radius of a reconstruction, in coarse voxels. The normals come from the
/// model (the normal map), not from an estimator on the staircase, so the ball need only average
/// the staircase's positions; the paper's 0.2 of the object size (Fig. 16) rounds the bunny's thin
/// parts and loses to the uncorrected operator (docs/regularization.md, "Reconstruction from a
/// normal map"). The same as the floor of voxels from a file, kVoxelMinCurvatureRadius.
inline constexpr double kReconstructionCurvatureRadiusVoxels = 2.0;

/// Every quad split into s x s quads, s = 2^levels, by bilinear interpolation of its corners
/// (exact on planar surfels). A point on an edge is shared by the faces that meet there, so a
/// closed mesh stays closed. Vertex order: the input's vertices, then the edges' inner points (edge
/// by edge, in build_edges order), then the faces' inner points; faces: s^2 per input face, in
/// its order, each oriented as its parent. h of the result = h / s. levels in [0, 6]; throws
/// InputError otherwise or for a mesh that fails validate().
SurfelMesh subdivide_quads(const SurfelMesh& mesh, int levels);

/// Unit vertex normals of a triangle mesh: the normalized sum of the incident triangles' area-
/// weighted normals (#V x 3; zero rows for vertices of no triangle).
Eigen::MatrixX3d triangle_mesh_vertex_normals(const Eigen::MatrixX3d& V, const TriangleIndices& T);

/// The normal map at `mesh`: at every vertex and face centroid, the fine mesh's vertex normals
/// interpolated at the closest point (barycentric weights), normalized. Throws NumericalError when
/// an interpolated normal vanishes (opposite normals across a sharp fold).
NormalFields sample_normal_map(const SurfelMesh& mesh, const TriangleLocator& fine,
                               const Eigen::MatrixX3d& fine_vertex_normals);

/// Mean and largest distance of the mesh's vertices to the fine mesh.
struct DistanceToMesh {
  double mean = 0, max = 0;
};
DistanceToMesh distance_to_mesh(const SurfelMesh& mesh, const TriangleLocator& fine);

/// Mean angle, in degrees, between the mesh's own geometric vertex normals (what a viewer shades
/// with, surface_quality.hpp) and the normal map at each vertex (the fine mesh's vertex normals
/// interpolated at its closest point): how far the shading of the result is from the model's, which
/// the distance alone does not show (a staircase's ripples cost little distance and much angle).
double normal_angle_to_map(const SurfelMesh& mesh, const TriangleLocator& fine,
                           const Eigen::MatrixX3d& fine_vertex_normals);

}  // namespace corrlap
