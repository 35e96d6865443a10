#pragma once
// The checks a surface goes through before the steps that need them, with one policy for every
// front end: the regularizations need a closed surface and, by default, a manifold one; the
// solvers' problems take natural boundary conditions on an open one.
#include <corrlap/core/surfel_mesh.hpp>
#include <string>

namespace corrlap {

/// The surfaces the regularization and the normal-map reconstruction accept (docs/regularization.md):
/// closed and manifold (InputError naming the boundary edges, or the non-manifold edges and
/// vertices). Surfaces extracted from voxels always are manifold (extract_surface splits pinched
/// pointels into sheets, docs/math.md §1.4); a quad mesh given as it is may not be, and no sheet
/// rule applies to it, so the error asks to split it.
void check_regularizable(const SurfelMesh& mesh);

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
