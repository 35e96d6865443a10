#include "distributed_surface.hpp"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <corrlap/backends/petsc.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/surface/partial_digitization.hpp>
#include <corrlap/surface/surfel_order.hpp>
#include <stdexcept>
#include <unordered_map>

#include "detail/neighbours.hpp"

namespace corrlap {

namespace {

using distributed_detail::exchange;
using distributed_detail::pointel_key;

// Per rank, `per_rank` values of this rank gathered from every rank (rank-major).
std::vector<std::int64_t> all_gather(const std::vector<std::int64_t>& mine, int ranks) {
  std::vector<std::int64_t> all(mine.size() * std::size_t(ranks));
  MPI_Allgather(mine.data(), int(mine.size()), MPI_INT64_T, all.data(), int(mine.size()), MPI_INT64_T, MPI_COMM_WORLD);
  return all;
}

// Where this rank's items of each orientation group start, and how many the group has over all
// ranks: the prefix sums of the ranks' counts per group (ranks in order of x, as the serial ids).
struct GroupOffsets {
  std::array<std::int64_t, 2> base{0, 0}, total{0, 0};
};
GroupOffsets group_offsets(const std::array<std::int64_t, 2>& mine, int rank, int ranks) {
  const std::vector<std::int64_t> counts = all_gather({mine[0], mine[1]}, ranks);
  GroupOffsets o;
  for (int r = 0; r < ranks; ++r)
    for (std::size_t g = 0; g < 2; ++g) {
      o.total[g] += counts[2 * std::size_t(r) + g];
      if (r < rank) o.base[g] += counts[2 * std::size_t(r) + g];
    }
  return o;
}

// Index of `key` in a list of (key, value...) records of `stride` values sorted by key, or -1.
std::int64_t find_record(const std::vector<std::int64_t>& records, std::size_t stride, std::int64_t key) {
  std::size_t lo = 0, hi = records.size() / stride;
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (records[mid * stride] < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < records.size() / stride && records[lo * stride] == key ? std::int64_t(lo) : -1;
}

}  // namespace

DistributedSurface distributed_surface(const ImplicitShape& shape, const DigitizationParams& params) {
  return distributed_surface(implicit_slab_source(shape, params));
}

DistributedSurface distributed_surface(const SlabSource& source) {
  ensure_petsc_runtime();  // MPI
  DistributedSurface d;
  MPI_Comm_rank(MPI_COMM_WORLD, &d.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &d.ranks);
  const int below = d.rank > 0 ? d.rank - 1 : MPI_PROC_NULL;
  const int above = d.rank + 1 < d.ranks ? d.rank + 1 : MPI_PROC_NULL;
  const Eigen::Vector3i lower = source.lower;
  d.slab = slab_of(source.lower, source.upper, d.rank, d.ranks);

  // 1. The slab's voxels and one column each side: the +x one decides the x-surfels between this
  //    slab and the next, the -x one the split test of the pointels on the lower plane. A source
  //    that fails (a bad file) fails on every rank alike: each reads the same header and values.
  const VoxelGrid grid = collective_slab_voxels(source, d.slab.first - 1, d.slab.last + 1);
  d.grid_lower = grid.lower();
  d.grid_upper = grid.upper();

  // 2. Owned surfels, in serial face order: extract_surfels orders the slab's surfels like the
  //    whole grid's (the order is invariant under translation); keep those of the slab's columns.
  std::vector<Surfel> surfels;
  std::array<std::int64_t, 2> group_count{0, 0};  // negative, positive (docs/math.md §1.4)
  for (const Surfel& s : extract_surfels(grid))
    if (s.lower_voxel.x() >= d.slab.first && s.lower_voxel.x() <= d.slab.last) {
      surfels.push_back(s);
      ++group_count[s.positive() ? 1 : 0];
    }
  const GroupOffsets face_offsets = group_offsets(group_count, d.rank, d.ranks);
  const auto& face_base = face_offsets.base;
  const auto& face_total = face_offsets.total;
  d.num_faces = face_total[0] + face_total[1];
  if (d.num_faces == 0)
    throw InputError(
        "surface extraction: the volume has no surfel (it is empty, full, or touches no voxel pair inside the box)");
  const int F = int(surfels.size());
  d.face_ids.resize(std::size_t(F));
  for (int f = 0; f < F; ++f) {
    const std::size_t g = surfels[std::size_t(f)].positive() ? 1 : 0;
    // Faces of group 1 follow every face of group 0; within a group the ranks follow x.
    d.face_ids[std::size_t(f)] = (g == 1 ? face_total[0] : 0) + face_base[g] + (g == 1 ? f - group_count[0] : f);
  }

  // 3. Local vertices in order of first appearance among the owned faces, with the group of that
  //    face (local faces are group 0 first, so it is the smallest group using the vertex).
  std::unordered_map<std::uint64_t, int> local_of;
  local_of.reserve(std::size_t(F) + 16);
  std::vector<Eigen::Vector3i> pointels;
  std::vector<int> first_group;
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> faces(F, 4);
  for (int f = 0; f < F; ++f)
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3i q = surfel_corner_pointel(surfels[std::size_t(f)], c);
      const auto [it, added] = local_of.try_emplace(pointel_key(q, lower), int(pointels.size()));
      if (added) {
        pointels.push_back(q);
        first_group.push_back(surfels[std::size_t(f)].positive() ? 1 : 0);
      }
      faces(f, c) = it->second;
    }
  const int V = int(pointels.size());

  // Serial ids are ids of first appearance: a pointel with several vertices would break them.
  std::int64_t splits = 0;
  for (const Eigen::Vector3i& q : pointels) splits += pointel_may_split(grid, q) ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &splits, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (splits > 0)
    throw InputError("distributed surface: " + std::to_string(splits) +
                     " pointels where extract_surface may split vertices (voxels touching along an edge or a corner, "
                     "or surfels on the box's faces): not supported by the distributed front end yet");

  // 4. Owners of the vertices on the planes shared with the neighbours (pointel x = first: the
  //    rank below; x = last + 1: the rank above): (key, first group) records sorted by key.
  auto plane_records = [&](int x) {
    std::vector<std::pair<std::int64_t, int>> list;
    for (int v = 0; v < V; ++v)
      if (pointels[std::size_t(v)].x() == x)
        list.push_back({std::int64_t(pointel_key(pointels[std::size_t(v)], lower)), v});
    std::sort(list.begin(), list.end());
    return list;
  };
  const auto low_plane = plane_records(d.slab.first), high_plane = plane_records(d.slab.last + 1);
  auto records = [&](const std::vector<std::pair<std::int64_t, int>>& list) {
    std::vector<std::int64_t> out;
    for (const auto& [key, v] : list) out.insert(out.end(), {key, first_group[std::size_t(v)]});
    return out;
  };
  const std::vector<std::int64_t> from_below = exchange(records(high_plane), above, below);
  const std::vector<std::int64_t> from_above = exchange(records(low_plane), below, above);
  // The first appearance is in the smallest group, then the lower rank: with equal groups the
  // rank below wins.
  std::vector<std::uint8_t> owned(static_cast<std::size_t>(V), 1);
  for (const auto& [key, v] : low_plane)
    if (const std::int64_t i = find_record(from_below, 2, key); i >= 0)
      owned[std::size_t(v)] = first_group[std::size_t(v)] < from_below[std::size_t(2 * i + 1)];
  for (const auto& [key, v] : high_plane)
    if (const std::int64_t i = find_record(from_above, 2, key); i >= 0)
      owned[std::size_t(v)] = first_group[std::size_t(v)] <= from_above[std::size_t(2 * i + 1)];

  // 5. Serial ids and rows of the owned vertices: prefix sums of the owners' counts per group.
  std::array<std::int64_t, 2> owned_count{0, 0};
  for (int v = 0; v < V; ++v)
    if (owned[std::size_t(v)]) ++owned_count[std::size_t(first_group[std::size_t(v)])];
  const GroupOffsets vertex_offsets = group_offsets(owned_count, d.rank, d.ranks);
  const auto& vertex_base = vertex_offsets.base;
  const auto& vertex_total = vertex_offsets.total;
  d.num_vertices = vertex_total[0] + vertex_total[1];
  d.row_begin = vertex_base[0] + vertex_base[1];
  std::vector<std::int64_t> serial(static_cast<std::size_t>(V), -1), row(static_cast<std::size_t>(V), -1);
  std::array<std::int64_t, 2> next{vertex_base[0], vertex_total[0] + vertex_base[1]};
  std::int64_t next_row = d.row_begin;
  for (int v = 0; v < V; ++v)
    if (owned[std::size_t(v)]) {
      serial[std::size_t(v)] = next[std::size_t(first_group[std::size_t(v)])]++;
      row[std::size_t(v)] = next_row++;
    }
  d.num_owned = int(next_row - d.row_begin);

  // 6. Ids of the vertices owned by a neighbour: each rank sends (serial id, row) of its plane
  //    records, -1 where it is not the owner, in the order of the records it sent before.
  auto ids_of = [&](const std::vector<std::pair<std::int64_t, int>>& list) {
    std::vector<std::int64_t> out;
    for (const auto& [key, v] : list) out.insert(out.end(), {serial[std::size_t(v)], row[std::size_t(v)]});
    return out;
  };
  const std::vector<std::int64_t> ids_below = exchange(ids_of(high_plane), above, below);
  const std::vector<std::int64_t> ids_above = exchange(ids_of(low_plane), below, above);
  auto adopt = [&](const std::vector<std::pair<std::int64_t, int>>& list, const std::vector<std::int64_t>& keys,
                   const std::vector<std::int64_t>& ids) {
    for (const auto& [key, v] : list) {
      if (owned[std::size_t(v)]) continue;
      const std::int64_t i = find_record(keys, 2, key);
      if (i < 0 || ids[std::size_t(2 * i)] < 0)
        throw std::logic_error("distributed surface: a shared vertex has no owner");
      serial[std::size_t(v)] = ids[std::size_t(2 * i)];
      row[std::size_t(v)] = ids[std::size_t(2 * i + 1)];
    }
  };
  adopt(low_plane, from_below, ids_below);
  adopt(high_plane, from_above, ids_above);

  // 7. Local order: owned vertices first (their rows are then row_begin + v), then the others.
  std::vector<int> order;
  order.reserve(std::size_t(V));
  for (int pass = 0; pass < 2; ++pass)
    for (int v = 0; v < V; ++v)
      if (bool(owned[std::size_t(v)]) == (pass == 0)) order.push_back(v);
  std::vector<int> new_index(static_cast<std::size_t>(V));
  for (int i = 0; i < V; ++i) new_index[std::size_t(order[std::size_t(i)])] = i;
  d.mesh.h = source.h;
  d.mesh.surfels = std::move(surfels);
  d.mesh.faces.resize(F, 4);
  for (int f = 0; f < F; ++f)
    for (int c = 0; c < 4; ++c) d.mesh.faces(f, c) = new_index[std::size_t(faces(f, c))];
  d.mesh.positions.resize(V, 3);
  d.vertex_ids.resize(std::size_t(V));
  d.rows.resize(std::size_t(V));
  for (int i = 0; i < V; ++i) {
    const int v = order[std::size_t(i)];
    for (int a = 0; a < 3; ++a) d.mesh.positions(i, a) = pointel_coordinate(pointels[std::size_t(v)][a], source.h);
    d.vertex_ids[std::size_t(i)] = serial[std::size_t(v)];
    d.rows[std::size_t(i)] = row[std::size_t(v)];
  }
  return d;
}

}  // namespace corrlap
