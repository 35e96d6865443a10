#include "slab.hpp"

#include <corrlap/core/error.hpp>
#include <cstdint>
#include <string>

namespace corrlap {

Slab slab_of(const Eigen::Vector3i& lower, const Eigen::Vector3i& upper, int rank, int ranks) {
  const std::int64_t n = std::int64_t(upper.x()) - lower.x() + 1;
  if (ranks < 1 || rank < 0 || rank >= ranks) throw InputError("slab: rank out of range");
  if (n < ranks)
    throw InputError("distributed digitization: the box has " + std::to_string(n) + " voxel columns along x for " +
                     std::to_string(ranks) + " ranks (at least one each)");
  Slab s;
  s.first = lower.x() + int(n * rank / ranks);
  s.last = lower.x() + int(n * (rank + 1) / ranks) - 1;
  return s;
}

}  // namespace corrlap
