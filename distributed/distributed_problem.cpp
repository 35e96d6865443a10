#include "distributed_problem.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/volume_io.hpp>
#include <string>
#include <variant>

#include "distributed_ii_normals.hpp"

namespace corrlap {

namespace {

// load_surface refuses a degenerate voxel-to-physical map, so such volumes stay with the serial
// front end, which says why.
void check_volume_geometry(const VolumeGeometry& g, const std::string& path) {
  const bool finite = g.spacing.allFinite() && g.origin.allFinite() && g.direction.allFinite();
  if (!finite || !(g.spacing.minCoeff() > 0.0) || !(std::abs(g.direction.determinant()) > 1e-12))
    throw InputError("distributed front end: volume file '" + path + "' has a degenerate voxel-to-physical map");
}

}  // namespace

DistributedProblem::DistributedProblem(const SurfaceInput& input, const NormalRequest& normals) {
  if (!normals.face_normals_file.empty() || !normals.vertex_normals_file.empty() || normals.face_normals.rows() > 0 ||
      normals.vertex_normals.rows() > 0)
    throw InputError("distributed front end: given normals are not distributed");
  if (const auto* s = std::get_if<ImplicitShapeInput>(&input)) {
    check_grid_step(s->digitization.h, "shape '" + s->shape + "'");
    shape_ = std::make_unique<ImplicitShape>(make_implicit_shape(s->shape, s->center));
    source_ = implicit_slab_source(*shape_, s->digitization);
    frame_ = VoxelFrame(s->digitization.h, Eigen::Vector3d::Zero());  // load_surface's for shapes
  } else if (const auto* v = std::get_if<VolumeFileInput>(&input)) {
    // load_surface's reading of a volume file (pipeline/load_surface.cpp, volume_voxels).
    if (!std::isfinite(v->inside.value))
      throw InputError("distributed front end: the inside rule's value is not finite");
    if (v->h) check_grid_step(*v->h, "volume file '" + v->path + "'");
    VolumeReadOptions options;
    options.inside = v->inside;
    options.h = v->h.value_or(0.0);
    options.centered = true;
    options.raw_dimensions = v->raw_dimensions;
    const VolumeVoxelBox box = read_volume_voxel_box(v->path, options);
    check_volume_geometry(box.geometry, v->path);
    if (box.geometry.isotropic()) {
      source_ = volume_slab_source(v->path, options);
      frame_ = volume_voxel_frame(box.lower, box.h, box.geometry);
    } else {
      // load_surface's cubes of the finest spacing, with their own box, step and geometry.
      const IsotropicResampling resampling = isotropic_resampling(box.size, box.geometry, v->h);
      source_ = resampled_volume_slab_source(v->path, options, resampling);
      frame_ = volume_voxel_frame(resampling.lower(), resampling.h, resampling.geometry);
    }
  } else {
    throw InputError("distributed front end: only implicit shapes and volume files are distributed");
  }
  normals_ = effective_normal_source(normals.source, shape_.get(), /*grid=*/nullptr);
  if (normals_ == NormalSource::Auto) normals_ = NormalSource::II;  // a volume: its voxels
  if (normals_ != NormalSource::True && normals_ != NormalSource::II)
    throw InputError(std::string("distributed front end: the normals '") + to_string(normals_) +
                     "' are not distributed");
  if (normals_ == NormalSource::True && !shape_)
    throw InputError("distributed front end: true normals need an implicit shape");

  surface_ = distributed_surface(source_);
  if (normals_ == NormalSource::True) {
    fem_ = std::make_unique<DistributedFem>(surface_, true_face_normals(*shape_, surface_.mesh));
    // resolve_normals': the normalized sums of the true face normals around each vertex, whose
    // fans reach one column beyond the slab.
    const NearSlabNormals near = true_normals_near_slab(*shape_, source_, surface_, 1);
    vertex_normals_.resize(surface_.num_owned, 3);
    for (int v = 0; v < surface_.num_owned; ++v)
      vertex_normals_.row(v) = near.vertex_normals.row(near.owned_vertices[std::size_t(v)]);
    return;
  }
  // resolve_normals' II parameters and checks, then the same face normals as ii_face_normals.
  ii_ = normals.ii ? *normals.ii : default_ii_params(shape_ != nullptr);
  check_ii_params(ii_);
  DistributedNormals n = distributed_ii_normals(source_, surface_, ii_);
  fem_ = std::make_unique<DistributedFem>(surface_, n.face_normals);
  vertex_normals_ = std::move(n.vertex_normals);
  face_normals_ = std::move(n.face_normals);
}

NearSlabNormals DistributedProblem::near_slab(int columns) const {
  if (normals_ == NormalSource::True) return true_normals_near_slab(*shape_, source_, surface_, columns);
  return distributed_ii_normals_near_slab(source_, surface_, ii_, columns, &face_normals_);
}

DistributedProblem::~DistributedProblem() = default;

std::unique_ptr<DistributedProblem> make_distributed_problem(const SurfaceInput& input, const NormalRequest& normals,
                                                             std::string& refused) {
  try {
    return std::make_unique<DistributedProblem>(input, normals);
  } catch (const InputError& e) {
    refused = e.what();
    return nullptr;
  }
}

}  // namespace corrlap
