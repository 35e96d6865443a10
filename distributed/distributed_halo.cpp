#include "distributed_halo.hpp"

#include <mpi.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/surface/surfel_order.hpp>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "detail/neighbours.hpp"

namespace corrlap {

namespace {

using distributed_detail::pointel_key;

}  // namespace

DistributedHalo distributed_halo(const SlabSource& source, const DistributedSurface& surface, int width) {
  if (width < 0)
    throw InputError("distributed halo: the width must be at least 0 columns, got " + std::to_string(width));
  DistributedHalo halo;
  halo.width = width;
  halo.range.first = std::max(source.lower.x(), surface.slab.first - width);
  halo.range.last = std::min(source.upper.x(), surface.slab.last + width);
  // The column after the range decides the x-surfels of its last column (as for the slab).
  halo.grid = collective_slab_voxels(source, halo.range.first - 1, halo.range.last + 1);

  // 1. Faces per (group, column) of every rank's slab: the serial id of a face is the number of
  //    faces of its group in the columns before its own (plus, for group 1, all of group 0), plus
  //    its index within its column (docs/math.md §1.4: sorted by (positive, kc_x, kc_y, kc_z), and
  //    the lower voxel's x orders kc_x).
  const int n = source.upper.x() - source.lower.x() + 1;
  std::vector<std::int64_t> mine(2 * std::size_t(surface.slab.columns()), 0);
  for (const Surfel& s : surface.mesh.surfels)
    ++mine[2 * std::size_t(s.lower_voxel.x() - surface.slab.first) + (s.positive() ? 1 : 0)];
  std::vector<int> counts(static_cast<std::size_t>(surface.ranks)), displs(static_cast<std::size_t>(surface.ranks));
  for (int r = 0; r < surface.ranks; ++r) {
    const Slab s = slab_of(source.lower, source.upper, r, surface.ranks);
    counts[std::size_t(r)] = 2 * s.columns();
    displs[std::size_t(r)] = 2 * (s.first - source.lower.x());
  }
  std::vector<std::int64_t> per_column(2 * std::size_t(n), 0);
  MPI_Allgatherv(mine.data(), int(mine.size()), MPI_INT64_T, per_column.data(), counts.data(), displs.data(),
                 MPI_INT64_T, MPI_COMM_WORLD);
  // first_id[2 c + g]: serial id of the first face of group g in column c.
  std::vector<std::int64_t> first_id(2 * std::size_t(n), 0);
  std::int64_t group0 = 0;
  for (int c = 0; c < n; ++c) group0 += per_column[2 * std::size_t(c)];
  std::int64_t next[2] = {0, group0};
  for (int c = 0; c < n; ++c)
    for (std::size_t g = 0; g < 2; ++g) {
      first_id[2 * std::size_t(c) + g] = next[g];
      next[g] += per_column[2 * std::size_t(c) + g];
    }

  // 2. The range's surfels in serial order (extract_surfels sorts like the whole grid), their ids.
  std::vector<Surfel> surfels;
  for (const Surfel& s : extract_surfels(halo.grid))
    if (s.lower_voxel.x() >= halo.range.first && s.lower_voxel.x() <= halo.range.last) surfels.push_back(s);
  const int F = int(surfels.size());
  halo.face_ids.resize(std::size_t(F));
  std::vector<std::int64_t> seen(2 * std::size_t(n), 0);
  for (int f = 0; f < F; ++f) {
    const Surfel& s = surfels[std::size_t(f)];
    const std::size_t k = 2 * std::size_t(s.lower_voxel.x() - source.lower.x()) + (s.positive() ? 1 : 0);
    halo.face_ids[std::size_t(f)] = first_id[k] + seen[k]++;
  }
  for (int c = halo.range.first; c <= halo.range.last; ++c)
    for (std::size_t g = 0; g < 2; ++g) {
      const std::size_t k = 2 * std::size_t(c - source.lower.x()) + g;
      if (seen[k] != per_column[k])
        throw std::logic_error(
            "distributed halo: a column's surfels differ from its owner's (a source that is not "
            "the same on every rank?)");
    }

  // 3. Local vertices in order of first appearance, identified by their pointels.
  std::unordered_map<std::uint64_t, int> local_of;
  local_of.reserve(std::size_t(F) + 16);
  halo.mesh.h = source.h;
  halo.mesh.faces.resize(F, 4);
  for (int f = 0; f < F; ++f)
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3i q = surfel_corner_pointel(surfels[std::size_t(f)], c);
      const auto [it, added] = local_of.try_emplace(pointel_key(q, source.lower), int(halo.pointels.size()));
      if (added) halo.pointels.push_back(q);
      halo.mesh.faces(f, c) = it->second;
    }
  const int V = int(halo.pointels.size());
  halo.mesh.positions.resize(V, 3);
  for (int v = 0; v < V; ++v)
    for (int a = 0; a < 3; ++a)
      halo.mesh.positions(v, a) = pointel_coordinate(halo.pointels[std::size_t(v)][a], source.h);
  halo.mesh.surfels = std::move(surfels);

  // 4. The owned faces among them (the slab lies in the range, so each is here) and their vertices'
  //    serial ids.
  std::unordered_map<std::int64_t, int> face_of;
  face_of.reserve(std::size_t(F) + 16);
  for (int f = 0; f < F; ++f) face_of.emplace(halo.face_ids[std::size_t(f)], f);
  halo.vertex_ids.assign(std::size_t(V), -1);
  halo.owned_faces.resize(surface.face_ids.size());
  for (std::size_t f = 0; f < surface.face_ids.size(); ++f) {
    const auto it = face_of.find(surface.face_ids[f]);
    if (it == face_of.end()) throw std::logic_error("distributed halo: an owned face is missing from its halo");
    halo.owned_faces[f] = it->second;
    for (int c = 0; c < 4; ++c)
      halo.vertex_ids[std::size_t(halo.mesh.faces(it->second, c))] =
          surface.vertex_ids[std::size_t(surface.mesh.faces(Eigen::Index(f), c))];
  }
  return halo;
}

}  // namespace corrlap
