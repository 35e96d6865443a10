#pragma once
// The measures `corrlap regularize` reports, over the ranks of the distributed front end without
// gathering the surface (docs/distributed.md, "Writing the outputs"): areas, extents, components and
// the quality against an implicit shape. Each equals the serial measure of the whole surface up to
// the order of its sums.
#include <Eigen/Core>
#include <corrlap/regularization/solution_check.hpp>
#include <corrlap/regularization/surface_quality.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <optional>
#include <string>

#include "distributed_halo.hpp"
#include "distributed_surface.hpp"

namespace corrlap {

/// surface_area of the whole surface with its owned vertices at `positions` (#owned by 3). Collective.
double distributed_surface_area(const DistributedSurface& s, const Eigen::MatrixX3d& positions);

/// check_solution(input, result, residual, what) of the whole surface: the staircase's owned
/// vertices at `before`, the result's at `after` (#owned by 3 each). Throws its NumericalError on
/// every rank. Collective.
SolutionCheck distributed_check_solution(const DistributedSurface& s, const Eigen::MatrixX3d& before,
                                         const Eigen::MatrixX3d& after, std::optional<double> residual,
                                         const std::string& what);

/// compute_mesh_info(whole mesh).components: each rank joins its faces, and rank 0 joins the pieces
/// that share vertices (a graph of the slabs' boundary vertices, not of the surface). Collective.
int distributed_components(const DistributedSurface& s);

/// Columns of the halo distributed_measure_against_shape needs for the curvature radius r and
/// positions at most `displacement` from their staircase ones.
int quality_halo_columns(double r, double displacement, double h);

/// measure_against_shape(whole mesh, shape, r) of the surface with its owned vertices at
/// `positions` (#owned by 3): the mean distance and normal angle over every vertex, and the mean
/// error of the corrected mean curvature, computed per slab from `halo` (distributed_halo of the
/// surface's source, quality_halo_columns wide or more: InputError otherwise). Collective.
SurfaceQuality distributed_measure_against_shape(const DistributedSurface& s, const DistributedHalo& halo,
                                                 const Eigen::MatrixX3d& positions, double displacement,
                                                 const ImplicitShape& shape, double r);

}  // namespace corrlap
