#pragma once
// The surface and operators of a command on the distributed front end (docs/distributed.md), set
// up in one place for every caller: the slab source of the surface input, the distributed surface,
// the face normals the fem method needs and the assembled operators. The CLI's solve and eigs run
// their problem on it; choose_front_end (pipeline/front_end.hpp) decides when.
#include <corrlap/estimators/normal_resolution.hpp>
#include <corrlap/pipeline/load_surface.hpp>
#include <corrlap/surface/implicit_shape.hpp>
#include <memory>
#include <string>

#include "distributed_fem.hpp"
#include "distributed_surface.hpp"
#include "near_slab.hpp"
#include "slab_source.hpp"

namespace corrlap {

class DistributedProblem {
 public:
  /// Collective over MPI_COMM_WORLD. `input`: an ImplicitShapeInput, or a VolumeFileInput read as
  /// load_surface reads it (centred, anisotropic voxels resampled to cubes, its step h or 2 / the
  /// longest side). `normals`: the source True or II, or Auto (true for a shape, II for a volume,
  /// as resolve_normals); its `ii`, when unset, is default_ii_params for the input, as
  /// resolve_normals would use.
  ///
  /// Throws InputError, on every rank alike, for anything whose result would not be the serial
  /// front end's: other inputs and normal sources, given normals, a volume with a degenerate
  /// voxel-to-physical map (load_surface refuses it), and the refusals of
  /// distributed_surface, distributed_ii_normals and DistributedFem. The caller then runs the
  /// serial front end, which computes the result or gives its own error.
  DistributedProblem(const SurfaceInput& input, const NormalRequest& normals);
  ~DistributedProblem();
  DistributedProblem(const DistributedProblem&) = delete;
  DistributedProblem& operator=(const DistributedProblem&) = delete;

  const DistributedSurface& surface() const { return surface_; }
  const DistributedFem& fem() const { return *fem_; }
  /// load_surface's frame for the same input: world -> voxel index -> physical coordinates.
  const VoxelFrame& frame() const { return frame_; }
  /// Where the slabs' voxels come from (read again for halos).
  const SlabSource& source() const { return source_; }
  /// The normals used: True or II (Auto resolved).
  NormalSource normals() const { return normals_; }
  /// The implicit shape, or null for a volume.
  const ImplicitShape* shape() const { return shape_ ? shape_.get() : nullptr; }
  /// num_owned x 3: the unit normals of the owned vertices (the serial front end's vertex normals).
  const Eigen::MatrixX3d& vertex_normals() const { return vertex_normals_; }
  /// The surface within `columns` >= 1 columns of the slab with the same normals
  /// (near_slab.hpp), for the estimators that look beyond the slab. Collective.
  NearSlabNormals near_slab(int columns) const;

 private:
  // The slab source of a shape refers to it: it lives at a fixed address for the source's life.
  std::unique_ptr<ImplicitShape> shape_;
  SlabSource source_;
  VoxelFrame frame_;
  NormalSource normals_ = NormalSource::True;
  IIParams ii_;  // with II normals
  Eigen::MatrixX3d vertex_normals_;
  Eigen::MatrixX3d face_normals_;  // II: the owned faces' (the near-slab pieces reuse them)
  DistributedSurface surface_;
  std::unique_ptr<DistributedFem> fem_;
};

/// The DistributedProblem, or null when the distributed front end refused the input (an
/// InputError, thrown on every rank alike): `refused` then says why, for the note of a caller that
/// runs the serial front end instead. Other errors (a solver's, MPI's) are thrown.
std::unique_ptr<DistributedProblem> make_distributed_problem(const SurfaceInput& input, const NormalRequest& normals,
                                                             std::string& refused);

}  // namespace corrlap
