#include "surface_checks.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>

namespace corrlap {

void check_regularizable(const SurfelMesh& mesh) {
  const MeshInfo info = compute_mesh_info(mesh);
  if (!info.closed())
    throw InputError("the surface is open (" + std::to_string(info.boundary_edges) +
                     " boundary edges); the regularization is defined for closed surfaces");
  // Surfaces from voxels are split into manifold sheets at extraction; only a given mesh gets here.
  if (!info.manifold())
    throw InputError("the surface is not manifold (" + std::to_string(info.nonmanifold_edges) +
                     " non-manifold edges, " + std::to_string(info.nonmanifold_vertices) +
                     " non-manifold vertices); a quad mesh given as it is must be a closed 2-manifold: give each "
                     "sheet its own vertices at those edges and vertices (surfaces extracted from voxels are split "
                     "this way by corrlap itself)");
}

BoundaryCondition boundary_condition(const SurfelMesh& mesh) {
  BoundaryCondition bc;
  bc.boundary_edges = compute_mesh_info(mesh).boundary_edges;
  return bc;
}

std::string BoundaryCondition::note() const {
  if (closed()) return {};
  return "the surface is open (" + std::to_string(boundary_edges) +
         " boundary edges): natural (zero Neumann) boundary conditions are used";
}

std::string BoundaryCondition::label() const {
  if (closed()) return "closed";
  return "natural (zero Neumann) on " + std::to_string(boundary_edges) + " boundary edges";
}

}  // namespace corrlap
