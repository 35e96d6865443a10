#pragma once
// Digitization (or reading) and surface extraction of an implicit shape (or a volume) spread over the MPI ranks of
// MPI_COMM_WORLD: rank r digitizes only its slab of x (slab.hpp) and extracts and numbers only the
// surfels it owns. No rank ever holds the whole grid or the whole surface (docs/distributed.md).
//
// Numbering: faces and vertices get exactly the ids of the serial extract_surface on the whole
// grid (docs/math.md §1.4). Faces are sorted by (positive, kc_x, kc_y, kc_z) and the slabs are
// ordered along x, so a face's id is a prefix sum of per-rank counts within its orientation group.
// Vertices are numbered in order of first appearance, and a vertex first appears in the faces of
// one rank (its owner: the rank of the first face that uses it), within one group; the owners'
// counts per group give the ids by the same prefix sums. Surfaces whose pointels extract_surface
// would split into several vertices (pinched voxels, the box's faces) are refused.
//
// Rows of the distributed matrices: rank r owns the rows of the vertices it owns. Their serial ids
// form two ranges (one per group), PETSc needs one range per rank, so the rows use a rank-major
// order of the same vertices: rank r's rows are row_begin .. row_begin + num_owned - 1, its owned
// vertices by increasing serial id. `vertex_ids` maps local vertices to serial ids, `rows` to rows.
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <cstdint>
#include <vector>

#include "slab.hpp"
#include "slab_source.hpp"

namespace corrlap {

/// One rank's part of the surface.
struct DistributedSurface {
  int rank = 0, ranks = 1;
  Slab slab;                  ///< voxel columns whose surfels this rank owns
  Eigen::Vector3i grid_lower  ///< box of the voxels this rank digitized: its slab, one more
      = Eigen::Vector3i::Zero(),
      grid_upper = -Eigen::Vector3i::Ones();  ///< column each side (clipped to the box), all of y and z

  /// The faces owned here in serial order, on local vertices: mesh.faces is #Fl by 4 local vertex
  /// ids, mesh.positions #Vl by 3 (the owned vertices first, then the others of these faces),
  /// mesh.surfels #Fl, mesh.h the grid step.
  SurfelMesh mesh;
  std::vector<std::int64_t> face_ids;            ///< #Fl serial face ids (extract_surface's)
  std::vector<std::int64_t> vertex_ids;          ///< #Vl serial vertex ids (extract_surface's)
  std::vector<std::int64_t> rows;                ///< #Vl matrix rows (rank-major order, see above)
  int num_owned = 0;                             ///< local vertices 0 .. num_owned - 1 are owned here
  std::int64_t row_begin = 0;                    ///< row of local vertex v < num_owned: row_begin + v
  std::int64_t num_faces = 0, num_vertices = 0;  ///< of the whole surface
};

/// The distributed digitization (docs/math.md §1.2) and extraction (§1.3, §1.4) of `shape`: a
/// collective call of every rank of MPI_COMM_WORLD (MPI is started when needed). Throws InputError
/// (on every rank) when the surface is empty or has pointels extract_surface would split.
DistributedSurface distributed_surface(const ImplicitShape& shape, const DigitizationParams& params);
/// The same from any source of slab voxels (slab_source.hpp): a volume file read per slab gives
/// the faces, ids and positions of extract_surface(read_volume_as_voxels(path, options)).
DistributedSurface distributed_surface(const SlabSource& source);

}  // namespace corrlap
