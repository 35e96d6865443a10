#pragma once
// Loop subdivision of triangle meshes (C. Loop, "Smooth subdivision surfaces based on triangles",
// 1987): every triangle becomes four, old vertices and new edge points are smoothed, and the limit
// surface is C2 away from extraordinary vertices. The cotan comparison (paper §3.4, docs/math.md
// §10.6) refines its reference mesh this way to ~100 000 vertices before digitizing it.
#include <Eigen/Core>
#include <corrlap/core/polygon_mesh.hpp>

namespace corrlap {

struct TriangleMesh {
  Eigen::MatrixX3d positions;  ///< #V x 3
  TriangleIndices triangles;   ///< #T x 3, 0-based
};

/// One subdivision step: #V + #E vertices (the old ones first, in their order, then one per edge)
/// and 4 #T triangles. Interior rules: edge point 3/8 (a + b) + 1/8 (c + d); old vertex of valence
/// n: (1 - n beta) v + beta sum of neighbours, beta = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n.
/// Boundary rules (edges with one triangle): edge midpoint; vertex 3/4 v + 1/8 (its two boundary
/// neighbours), so that boundary curves refine as cubic B-splines. Throws InputError naming the
/// edge when an edge has more than two triangles or a triangle is degenerate in its indices.
TriangleMesh loop_subdivide(const TriangleMesh& mesh);

/// Subdivides until the mesh has at least `min_vertices` vertices (no step when it already has
/// them); returns the number of steps. InputError when that would need more than 8 steps.
int loop_refine(TriangleMesh& mesh, long long min_vertices);

}  // namespace corrlap
