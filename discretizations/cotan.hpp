#pragma once
// Cotan Laplacian and lumped mass on triangle meshes, for the paper's comparison against a
// triangle mesh (paper §3.4, docs/math.md §10.6). Registry name "cotan".
#include <Eigen/Core>
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/polygon_mesh.hpp>
#include <memory>

namespace corrlap {

/// Lumped mass of the cotan Laplacian.
enum class CotanMass {
  Barycentric,  ///< A_T / 3 per corner
  Voronoi,      ///< mixed Voronoi areas of Meyer et al. (pmp's formula, docs/math.md §5.1 step 4)
};

/// L = -sum_T K_T with K_T the 1/2-cot stiffness (L[i][j] = (cot a_ij + cot b_ij)/2 for an edge,
/// rows sum to 0, negative semi-definite, docs/math.md §0) and the diagonal mass. Throws InputError naming
/// the triangle when an index is out of range, a triangle repeats a vertex, a position is not
/// finite, or a triangle has zero area (up to round-off: A <= 1e-15 * longest edge^2).
Operators assemble_cotan(const Eigen::MatrixX3d& V, const TriangleIndices& T, CotanMass mass = CotanMass::Voronoi);

/// The registered discretization on a quad mesh: every quad (x0, x1, x2, x3) is split along the
/// diagonal x0-x2 into (x0, x1, x2) and (x0, x2, x3), then assemble_cotan. On a flat surfel the
/// diagonal gets weight 0 (both opposite angles are right), so the choice of diagonal does not
/// matter there. Parameter: mass = voronoi (default) | barycentric. No normals.
std::unique_ptr<Discretization> make_cotan();

}  // namespace corrlap
