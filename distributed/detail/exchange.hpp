#pragma once
// Exchanges of lists between every pair of ranks (internal): the outputs' fetches from and sums
// at the ranks that own vertices and faces.
#include <mpi.h>

#include <cstdint>
#include <numeric>
#include <vector>

namespace corrlap::detail {

/// Displacements of per-rank counts.
inline std::vector<int> displacements(const std::vector<int>& counts) {
  std::vector<int> d(counts.size(), 0);
  for (std::size_t r = 1; r < counts.size(); ++r) d[r] = d[r - 1] + counts[r - 1];
  return d;
}

/// Every rank sends to_rank[r] to rank r and gets what each rank sent it, in rank order, with the
/// counts received per rank in `from_counts`. Collective.
inline std::vector<std::int64_t> all_to_all(const std::vector<std::vector<std::int64_t>>& to_rank,
                                            std::vector<int>& from_counts) {
  const std::size_t P = to_rank.size();
  std::vector<int> counts(P);
  std::vector<std::int64_t> out;
  for (std::size_t r = 0; r < P; ++r) {
    counts[r] = int(to_rank[r].size());
    out.insert(out.end(), to_rank[r].begin(), to_rank[r].end());
  }
  from_counts.assign(P, 0);
  MPI_Alltoall(counts.data(), 1, MPI_INT, from_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  std::vector<std::int64_t> in(std::size_t(std::accumulate(from_counts.begin(), from_counts.end(), 0)));
  MPI_Alltoallv(out.data(), counts.data(), displacements(counts).data(), MPI_INT64_T, in.data(), from_counts.data(),
                displacements(from_counts).data(), MPI_INT64_T, MPI_COMM_WORLD);
  return in;
}

/// The same for doubles (`out` rank after rank), with the counts known on both sides. Collective.
inline std::vector<double> all_to_all(const std::vector<double>& out, const std::vector<int>& counts,
                                      const std::vector<int>& from_counts) {
  std::vector<double> in(std::size_t(std::accumulate(from_counts.begin(), from_counts.end(), 0)));
  MPI_Alltoallv(out.data(), counts.data(), displacements(counts).data(), MPI_DOUBLE, in.data(), from_counts.data(),
                displacements(from_counts).data(), MPI_DOUBLE, MPI_COMM_WORLD);
  return in;
}

/// Every rank's `mine` on every rank, rank after rank, with the counts per rank in `counts` (small
/// lists only). Collective.
inline std::vector<std::int64_t> gather_everywhere(const std::vector<std::int64_t>& mine, std::vector<int>& counts) {
  int count = int(mine.size());
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  counts.assign(std::size_t(ranks), 0);
  MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  std::vector<std::int64_t> all(std::size_t(std::accumulate(counts.begin(), counts.end(), 0)));
  MPI_Allgatherv(mine.data(), count, MPI_INT64_T, all.data(), counts.data(), displacements(counts).data(), MPI_INT64_T,
                 MPI_COMM_WORLD);
  return all;
}

}  // namespace corrlap::detail
