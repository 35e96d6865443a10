#pragma once
// A rank's slab widened by a halo of columns on each side, for the estimators that need the
// surface and voxels beyond the slab (II normals, curvature; docs/distributed.md, "Volumes per slab
// and the halo").
#include <Eigen/Core>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/core/voxel_grid.hpp>
#include <cstdint>
#include <vector>

#include "distributed_surface.hpp"
#include "slab.hpp"
#include "slab_source.hpp"

namespace corrlap {

/// The surfels of a widened range of columns, with local numbering.
///
/// Which parts are exact: `faces` holds every surfel whose lower voxel has x in `range` (and no
/// other), in serial face order, each with its serial face id. A vertex (pointel X, see
/// surfel_corner_pointel) is used by the surfels whose lower voxel x is X.x - 1 or X.x, so its fan of
/// faces here is the serial one exactly when X.x lies in [range.first + 1, range.last] (or the range
/// reaches the box's edge on that side, beyond which nothing lies). A face with lower voxel x in
/// [range.first + 1, range.last - 1] thus has complete fans at its four corners. The vertices near
/// the widened range's edges are corners of fewer faces than in the serial mesh.
struct DistributedHalo {
  int width = 0;  ///< columns added on each side of the slab
  Slab range;     ///< slab.first - width .. slab.last + width, clipped to the box
  /// Voxels of range.first - 1 .. range.last + 1 (clipped to the box), all of y and z, with their
  /// bits in the whole grid.
  VoxelGrid grid;
  /// The surfels of `range` in serial face order: mesh.surfels #Fh, mesh.faces #Fh by 4 local vertex
  /// ids (numbered in order of first appearance, as extract_surface does), mesh.positions #Vh by 3.
  SurfelMesh mesh;
  std::vector<std::int64_t> face_ids;     ///< #Fh serial face ids (extract_surface's)
  std::vector<Eigen::Vector3i> pointels;  ///< #Vh: the pointel of each local vertex (same on every rank)
  /// #Vh serial vertex ids of the vertices that are corners of the rank's owned faces, -1 for the
  /// others (the pointel identifies those).
  std::vector<std::int64_t> vertex_ids;
  /// #Fl: the local face (here) of each owned face of the DistributedSurface.
  std::vector<int> owned_faces;
};

/// The halo of `width` >= 0 columns around the slab of `surface`, which distributed_surface(source)
/// built: a collective call of every rank of MPI_COMM_WORLD (the serial face ids come from the
/// ranks' face counts per column, gathered once: 2 numbers per column of the box). The source is
/// read again for the widened columns. Throws InputError for a negative width.
DistributedHalo distributed_halo(const SlabSource& source, const DistributedSurface& surface, int width);

}  // namespace corrlap
