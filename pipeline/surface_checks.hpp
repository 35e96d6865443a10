#pragma once
// The checks a surface goes through before the steps that need them, with one policy for every
// front end: the regularizations need a closed surface and, by default, a manifold one; the
// solvers' problems take natural boundary conditions on an open one.
#include <corrlap/core/surfel_mesh.hpp>
#include <string>

namespace corrlap {

/// The surfaces the regularization and the normal-map reconstruction accept (docs/regularization.md):
/// closed (InputError naming the boundary edges otherwise) and, unless `allow_nonmanifold`,
/// manifold. Voxels that touch along an edge or at a corner only pinch the surface: its normals
/// and curvature are unreliable nearby and the solve moves it by several voxels, so that is
/// refused by default (InputError with parameter "allow_nonmanifold", naming the counts).
void check_regularizable(const SurfelMesh& mesh, bool allow_nonmanifold);

/// The boundary condition the solvers' problems get on this surface: none on a closed surface;
/// on an open one, natural (zero Neumann) conditions on its boundary edges, because every
/// discretization assembles L without boundary terms (docs/math.md §10.4).
struct BoundaryCondition {
  int boundary_edges = 0;
  bool closed() const { return boundary_edges == 0; }
  /// Empty when closed, else "the surface is open (N boundary edges): natural (zero Neumann)
  /// boundary conditions are used", for the user to read.
  std::string note() const;
  /// "closed" or "natural (zero Neumann) on N boundary edges", for reports.
  std::string label() const;
};
/// From compute_mesh_info(mesh).boundary_edges.
BoundaryCondition boundary_condition(const SurfelMesh& mesh);

}  // namespace corrlap
