#pragma once
// Small pieces shared by the distributed front end's files (internal): a pointel's key and the
// exchange of a list with the neighbouring ranks along x.
#include <mpi.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace corrlap::distributed_detail {

/// A pointel relative to the box's lower corner (pointels are >= lower), 21 bits per axis as the
/// surfel keys of extract_surface.
inline std::uint64_t pointel_key(const Eigen::Vector3i& q, const Eigen::Vector3i& lower) {
  const Eigen::Vector3i r = q - lower;
  return (std::uint64_t(r.x()) << 42) | (std::uint64_t(r.y()) << 21) | std::uint64_t(r.z());
}

/// Sends `out` to rank `to` and returns what rank `from` sent (MPI_PROC_NULL: nothing).
inline std::vector<std::int64_t> exchange(const std::vector<std::int64_t>& out, int to, int from) {
  std::int64_t count_out = std::int64_t(out.size()), count_in = 0;
  MPI_Sendrecv(&count_out, 1, MPI_INT64_T, to, 0, &count_in, 1, MPI_INT64_T, from, 0, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
  std::vector<std::int64_t> in(static_cast<std::size_t>(count_in));
  MPI_Sendrecv(out.data(), int(count_out), MPI_INT64_T, to, 1, in.data(), int(count_in), MPI_INT64_T, from, 1,
               MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return in;
}

}  // namespace corrlap::distributed_detail
