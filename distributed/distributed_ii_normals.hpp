#pragma once
// Integral-invariant normals (docs/math.md §7) of the faces and vertices a rank owns, from its slab
// widened by a halo (distributed_halo.hpp): bit for bit the serial ii_face_normals and
// ii_vertex_normals (docs/distributed.md, "Volumes per slab and the halo").
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/estimators/integral_invariant.hpp>
#include <cstdint>
#include <vector>

#include "distributed_surface.hpp"
#include "near_slab.hpp"
#include "slab_source.hpp"

namespace corrlap {

struct DistributedNormals {
  Eigen::MatrixX3d face_normals;    ///< #Fl: the owned faces, in the order of DistributedSurface::mesh
  Eigen::MatrixX3d vertex_normals;  ///< num_owned: the owned vertices (local 0 .. num_owned - 1)
  int halo_width = 0;               ///< columns of halo used on each side
  /// Balls of this rank whose seed's component, connected over the whole grid, is split into several
  /// pieces within the halo's voxels (joined only beyond it): their moments are the sum over the
  /// pieces (docs/distributed.md). A count, for tests and diagnostics.
  std::int64_t joined_balls = 0;
};

/// Columns of halo the II normals of a slab need for digital radius r_d: the balls reach
/// ceil(r_d) + 1 columns from their centres, the centres lie up to one column beyond the faces, and
/// the vertex normals of the slab's vertices need the faces one column beyond the slab.
int ii_halo_width(double digital_radius);

/// ii_face_normals(grid, mesh, params) of the owned faces and ii_vertex_normals of the owned
/// vertices, where grid is the source's whole grid and mesh its extract_surface, which
/// distributed_surface(source) built as `surface`; equal bit for bit (the moments are integers, the
/// rest is the same arithmetic in the same order). A collective call of every rank of
/// MPI_COMM_WORLD.
///
/// docs/math.md §7.1 restricts each ball to the 6-component of X of the surfel's inner voxel. A
/// halo can split one component into pieces that are connected only through voxels outside it, so
/// the ranks label the components of their slabs, join the labels across the slabs' boundaries
/// (gathered on rank 0: two numbers per component touching a boundary), and each ball sums the
/// moments of every piece of its seed's component. With params.shrink_on_thin_parts, docs/math.md
/// §7.2's smaller balls run on the same halo (ii_retry_thin_parts), with the serial's start radius
/// from the whole surface's extent. Throws InputError (on every rank) for the radii ii_face_normals
/// refuses.
DistributedNormals distributed_ii_normals(const SlabSource& source, const DistributedSurface& surface,
                                          const IIParams& params);

/// The NearSlabNormals of `columns` >= 1 columns with II normals: the II balls
/// run on a halo of ii_halo_width + columns - 1 columns. `owned_face_normals` (#Fl, optional):
/// distributed_ii_normals' normals of the owned faces, whose balls then are not run again. A
/// collective call of every rank of MPI_COMM_WORLD; throws InputError as distributed_ii_normals,
/// and for columns < 1.
NearSlabNormals distributed_ii_normals_near_slab(const SlabSource& source, const DistributedSurface& surface,
                                                 const IIParams& params, int columns,
                                                 const Eigen::MatrixX3d* owned_face_normals = nullptr);

}  // namespace corrlap
