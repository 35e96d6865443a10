#include "surface_checks.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/core/mesh_topology.hpp>

namespace corrlap {

void check_regularizable(const SurfelMesh& mesh, bool allow_nonmanifold) {
  const MeshInfo info = compute_mesh_info(mesh);
  if (!info.closed())
    throw InputError("the surface is open (" + std::to_string(info.boundary_edges) +
                     " boundary edges); the regularization is defined for closed surfaces");
  if (!info.manifold() && !allow_nonmanifold)
    throw InputError("the surface is not manifold (" + std::to_string(info.nonmanifold_edges) +
                         " non-manifold edges, " + std::to_string(info.nonmanifold_vertices) +
                         " non-manifold vertices: voxels touching along an edge or a corner); clean the volume (e.g. "
                         "a morphological opening; for a voxelized mesh, another resolution) or allow non-manifold "
                         "surfaces (allow_nonmanifold) to go on anyway",
                     "allow_nonmanifold");
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
