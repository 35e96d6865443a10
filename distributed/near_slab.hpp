#pragma once
// The surface near a rank's slab, with its normals: what the estimators that look beyond the slab
// read (the mean curvature, distributed_curvature.hpp). II normals: distributed_ii_normals.hpp.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdint>
#include <vector>

#include "distributed_surface.hpp"
#include "slab_source.hpp"

namespace corrlap {

/// The surface near a rank's slab with its normals, for estimators that look beyond the slab
/// (distributed_curvature.hpp).
struct NearSlabNormals {
  int columns = 0;  ///< the faces' lower voxels lie within this many columns of the slab
  /// Those faces in serial face order, on local vertices numbered by first appearance:
  /// mesh.faces #Fn by 4, mesh.positions #Vn by 3, mesh.surfels #Fn.
  SurfelMesh mesh;
  std::vector<std::int64_t> face_ids;     ///< #Fn serial face ids (extract_surface's)
  std::vector<Eigen::Vector3i> pointels;  ///< #Vn: the pointel of each local vertex
  /// #Fn x 3: the serial face normals, bit for bit.
  Eigen::MatrixX3d face_normals;
  /// #Vn x 3: the serial vertex normals, bit for bit, at least at the vertices whose faces are all
  /// here: those whose pointel x lies in [slab.first - columns + 1, slab.last + columns] (within
  /// the box); a unit vector at the others.
  Eigen::MatrixX3d vertex_normals;
  /// num_owned: the local vertex here of each owned vertex of the DistributedSurface.
  std::vector<int> owned_vertices;
};

/// near.vertex_normals from near.face_normals: the normalized sums of the faces around each vertex
/// (docs/math.md §1.5, as resolve_normals), serial bit for bit where a vertex's whole fan is here.
/// A vertex at the ragged edge whose faces here sum to zero gets one of their normals.
void set_vertex_normals_from_faces(NearSlabNormals& near);

/// The NearSlabNormals of `columns` >= 1 columns with the shape's true normals, as resolve_normals
/// gives them: true_face_normals, and the vertex normals from them. `source`
/// digitizes `shape` (implicit_slab_source). A collective call of every rank of MPI_COMM_WORLD;
/// throws InputError for columns < 1.
NearSlabNormals true_normals_near_slab(const ImplicitShape& shape, const SlabSource& source,
                                       const DistributedSurface& surface, int columns);

}  // namespace corrlap
