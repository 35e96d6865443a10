#pragma once
// Convolved trivial normals (docs/math.md §9.1's normals; the reference's
// ShortcutsGeometry::getCTrivialNormalVectors with its default t-ring 3): a weighted average of the
// surfel normals around each surfel, the input of the alignment regularization baseline.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>

namespace corrlap {

/// Unit normal per face (#F x 3, outward like the surfels'): the normalized sum, over the faces g
/// reached from f through shared edges without leaving the open ball of radius t (distances
/// between face centroids in grid units, i.e. divided by the grid step), of w(d) n_g with n_g the
/// trivial normal and w(d) = 1 - (t - d) / t^2. That weight is the reference's hat function of
/// height 1 and radius t applied to (t - d) / t: it grows from 1 - 1/t at the centre to 1 at the
/// rim, as the reference computes it (its DGtal test energy 1684.340 needs it). Faces beyond the
/// first one at distance >= t are not reached. Throws InputError for t <= 0.
Eigen::MatrixX3d convolved_trivial_normals(const SurfelMesh& mesh, double t_ring = 3.0);

}  // namespace corrlap
