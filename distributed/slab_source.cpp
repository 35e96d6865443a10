#include "slab_source.hpp"

#include <mpi.h>

#include <corrlap/core/error.hpp>
#include <corrlap/surface/partial_digitization.hpp>
#include <exception>
#include <string>

namespace corrlap {

SlabSource implicit_slab_source(const ImplicitShape& shape, const DigitizationParams& params) {
  SlabSource s;
  digitization_box(params, s.lower, s.upper);
  s.h = params.h;
  s.voxels = [&shape, params](int x_first, int x_last) { return digitize_x_range(shape, params, x_first, x_last); };
  return s;
}

SlabSource volume_slab_source(const std::string& path, const VolumeReadOptions& options) {
  const VolumeVoxelBox box = read_volume_voxel_box(path, options);
  SlabSource s;
  s.lower = box.lower;
  s.upper = box.upper;
  s.h = box.h;
  s.voxels = [path, options](int x_first, int x_last) {
    return read_volume_slab_as_voxels(path, options, x_first, x_last);
  };
  return s;
}

SlabSource resampled_volume_slab_source(const std::string& path, const VolumeReadOptions& options,
                                        const IsotropicResampling& resampling) {
  SlabSource s;
  s.lower = resampling.lower();
  s.upper = resampling.upper();
  s.h = resampling.h;
  s.voxels = [path, options, resampling](int x_first, int x_last) {
    return read_resampled_volume_slab(path, options, resampling, x_first, x_last);
  };
  return s;
}

VoxelGrid collective_slab_voxels(const SlabSource& source, int x_first, int x_last) {
  VoxelGrid grid;
  std::exception_ptr failure;
  try {
    grid = source.voxels(x_first, x_last);
  } catch (...) {
    failure = std::current_exception();
  }
  int rank = 0, failed = failure ? 1 : 0, first_failed = failure ? 0 : 1 << 30;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (failure) first_failed = rank;
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &first_failed, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (failure) std::rethrow_exception(failure);
  if (failed)
    throw InputError("distributed surface: rank " + std::to_string(first_failed) +
                     " could not read its slab of voxels (its own error says why)");
  return grid;
}

}  // namespace corrlap
