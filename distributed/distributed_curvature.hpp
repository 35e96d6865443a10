#pragma once
// The mean curvature at sites (docs/math.md §8.4) of a rank's vertices, from the surface near its
// slab: each cell of sites and each ball lies within a halo of columns, so the ranks compute the
// serial H of their vertices without the whole surface (docs/distributed.md).
#include <Eigen/Core>

#include "distributed_surface.hpp"
#include "near_slab.hpp"

namespace corrlap {

/// Columns beyond the slab whose faces H of the slab's vertices needs, for balls of radius r and
/// sites `spacing` apart on a grid of step h: a vertex's sites lie within `spacing` of it, a site's
/// choice reads the vertices of its cell (side 2 spacing), and its ball the faces within r; every
/// face there needs its corners' whole fans (one column more) and positions sit half a column
/// from their pointels. Throws InputError for a non-positive or non-finite argument.
int curvature_halo_columns(double r, double spacing, double h);

/// H at the owned vertices (local 0 .. num_owned - 1 of `surface`):
/// CorrectedCurvature::interpolated(mesh, vertex normals).mean_curvature_at_sites(r, spacing) of
/// the whole surface, to rounding (the same faces, sites and weights; sums in another order).
/// `near` holds the surface within curvature_halo_columns(r, spacing, h) columns of the slab or
/// more (InputError otherwise). Local to the rank.
Eigen::VectorXd distributed_mean_curvature(const DistributedSurface& surface, const NearSlabNormals& near, double r,
                                           double spacing);

}  // namespace corrlap
