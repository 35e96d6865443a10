#include "distributed_ii_normals.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <corrlap/surface/surfel_order.hpp>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "detail/neighbours.hpp"
#include "detail/run_components.hpp"
#include "distributed_halo.hpp"

namespace corrlap {

namespace {

using distributed_detail::exchange;

using distributed_detail::label_run_components;
using distributed_detail::RunComponents;

std::int64_t find_root(std::vector<std::int64_t>& parent, std::int64_t a) {
  while (parent[std::size_t(a)] != a) {
    parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
    a = parent[std::size_t(a)];
  }
  return a;
}

// The component over the whole grid of each component of this rank's slab (docs/math.md §7.1: the
// 6-components of X), as the smallest global label of its class. Global label of component l of
// rank r: offset[r] + l. A component crosses into the next slab through 6-adjacent voxels on
// either side of the plane between them; each rank finds those pairs with the labels the rank above
// sends for its first column, and rank 0 joins all pairs.
std::vector<std::int64_t> global_components(const RunComponents& own, const DistributedSurface& surface,
                                            std::vector<std::int64_t>& offset) {
  const int ranks = surface.ranks, rank = surface.rank;
  std::vector<std::int64_t> counts(static_cast<std::size_t>(ranks));
  const std::int64_t mine = own.count;
  MPI_Allgather(&mine, 1, MPI_INT64_T, counts.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
  offset.assign(std::size_t(ranks) + 1, 0);
  for (int r = 0; r < ranks; ++r) offset[std::size_t(r) + 1] = offset[std::size_t(r)] + counts[std::size_t(r)];
  const std::int64_t base = offset[std::size_t(rank)];

  // The global labels of the first column, row by row (-1: outside), for the rank below.
  const int below = rank > 0 ? rank - 1 : MPI_PROC_NULL, above = rank + 1 < ranks ? rank + 1 : MPI_PROC_NULL;
  std::vector<std::int64_t> first_column(std::size_t(own.rows_y) * std::size_t(own.rows_z), -1);
  for (int z = 0; z < own.rows_z; ++z)
    for (int y = 0; y < own.rows_y; ++y) {
      const int l = own.label_at({surface.slab.first, y + own.lower.y(), z + own.lower.z()});
      if (l >= 0) first_column[std::size_t(z) * std::size_t(own.rows_y) + std::size_t(y)] = base + l;
    }
  const std::vector<std::int64_t> next_column = exchange(first_column, below, above);
  std::vector<std::int64_t> pairs;
  for (std::size_t r = 0; r < next_column.size(); ++r) {
    if (next_column[r] < 0) continue;
    const int y = int(r % std::size_t(own.rows_y)), z = int(r / std::size_t(own.rows_y));
    const int l = own.label_at({surface.slab.last, y + own.lower.y(), z + own.lower.z()});
    if (l >= 0) pairs.insert(pairs.end(), {base + l, next_column[r]});
  }

  // Rank 0 joins every pair and sends each rank the roots of its components.
  int pair_count = int(pairs.size());
  std::vector<int> pair_counts(static_cast<std::size_t>(ranks)), pair_displs(static_cast<std::size_t>(ranks), 0);
  MPI_Gather(&pair_count, 1, MPI_INT, pair_counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<std::int64_t> all_pairs;
  std::vector<std::int64_t> parent;
  if (rank == 0) {
    for (int r = 1; r < ranks; ++r)
      pair_displs[std::size_t(r)] = pair_displs[std::size_t(r) - 1] + pair_counts[std::size_t(r) - 1];
    all_pairs.resize(std::size_t(pair_displs.back() + pair_counts.back()));
  }
  MPI_Gatherv(pairs.data(), pair_count, MPI_INT64_T, all_pairs.data(), pair_counts.data(), pair_displs.data(),
              MPI_INT64_T, 0, MPI_COMM_WORLD);
  std::vector<int> label_counts(static_cast<std::size_t>(ranks)), label_displs(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    label_counts[std::size_t(r)] = int(counts[std::size_t(r)]);
    label_displs[std::size_t(r)] = int(offset[std::size_t(r)]);
  }
  if (rank == 0) {
    parent.resize(std::size_t(offset.back()));
    std::iota(parent.begin(), parent.end(), std::int64_t{0});
    for (std::size_t i = 0; i + 1 < all_pairs.size(); i += 2) {
      const std::int64_t a = find_root(parent, all_pairs[i]), b = find_root(parent, all_pairs[i + 1]);
      if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    }
    for (std::int64_t l = 0; l < offset.back(); ++l) parent[std::size_t(l)] = find_root(parent, l);
  }
  std::vector<std::int64_t> roots(static_cast<std::size_t>(own.count));
  MPI_Scatterv(parent.data(), label_counts.data(), label_displs.data(), MPI_INT64_T, roots.data(), own.count,
               MPI_INT64_T, 0, MPI_COMM_WORLD);
  return roots;
}

// The global component of each component of the halo: its representative voxel's, asked of the
// rank whose slab holds that voxel.
std::vector<std::int64_t> halo_roots(const RunComponents& halo, const RunComponents& own,
                                     const std::vector<std::int64_t>& own_roots, const SlabSource& source,
                                     const DistributedSurface& surface) {
  const int ranks = surface.ranks;
  std::vector<Slab> slabs(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) slabs[std::size_t(r)] = slab_of(source.lower, source.upper, r, ranks);
  auto owner = [&](int x) {
    for (int r = 0; r < ranks; ++r)
      if (x >= slabs[std::size_t(r)].first && x <= slabs[std::size_t(r)].last) return r;
    throw std::logic_error("distributed II normals: a voxel outside every slab");
  };
  std::vector<std::vector<int>> asked(static_cast<std::size_t>(ranks));  // halo components asked of each rank
  std::vector<int> send_counts(std::size_t(ranks), 0), recv_counts(std::size_t(ranks), 0);
  for (int c = 0; c < halo.count; ++c) asked[std::size_t(owner(halo.representative[std::size_t(c)].x()))].push_back(c);
  std::vector<int> send_displs(std::size_t(ranks), 0), recv_displs(std::size_t(ranks), 0);
  std::vector<std::int64_t> queries;
  for (int r = 0; r < ranks; ++r) {
    send_displs[std::size_t(r)] = int(queries.size());
    for (int c : asked[std::size_t(r)]) {
      const Eigen::Vector3i& v = halo.representative[std::size_t(c)];
      queries.insert(queries.end(), {v.x(), v.y(), v.z()});
    }
    send_counts[std::size_t(r)] = int(queries.size()) - send_displs[std::size_t(r)];
  }
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (int r = 1; r < ranks; ++r)
    recv_displs[std::size_t(r)] = recv_displs[std::size_t(r) - 1] + recv_counts[std::size_t(r) - 1];
  std::vector<std::int64_t> received(std::size_t(recv_displs.back() + recv_counts.back()));
  MPI_Alltoallv(queries.data(), send_counts.data(), send_displs.data(), MPI_INT64_T, received.data(),
                recv_counts.data(), recv_displs.data(), MPI_INT64_T, MPI_COMM_WORLD);
  // Answers: one root per query (three numbers), in the same layout divided by three.
  std::vector<std::int64_t> answers(received.size() / 3);
  for (std::size_t q = 0; q < answers.size(); ++q) {
    const int l = own.label_at({int(received[3 * q]), int(received[3 * q + 1]), int(received[3 * q + 2])});
    if (l < 0) throw std::logic_error("distributed II normals: a neighbour's voxel is not inside here");
    answers[q] = own_roots[std::size_t(l)];
  }
  for (auto* v : {&send_counts, &send_displs, &recv_counts, &recv_displs})
    for (int& k : *v) k /= 3;
  std::vector<std::int64_t> replies(queries.size() / 3);
  MPI_Alltoallv(answers.data(), recv_counts.data(), recv_displs.data(), MPI_INT64_T, replies.data(), send_counts.data(),
                send_displs.data(), MPI_INT64_T, MPI_COMM_WORLD);
  std::vector<std::int64_t> roots(std::size_t(halo.count), -1);
  for (int r = 0; r < ranks; ++r)
    for (std::size_t i = 0; i < asked[std::size_t(r)].size(); ++i)
      roots[std::size_t(asked[std::size_t(r)][i])] = replies[std::size_t(send_displs[std::size_t(r)]) + i];
  return roots;
}

void add(BallMoments& sum, const BallMoments& m) {
  sum.m0 += m.m0;
  for (int k = 0; k < 3; ++k) sum.m1[k] += m.m1[k];
  for (int k = 0; k < 6; ++k) sum.m2[k] += m.m2[k];
}

// The II normals of the faces whose lower voxel lies within `columns` of the slab (`needed`, faces
// of `halo`, in its order), bit for bit the serial ones.
struct NormalsNearSlab {
  DistributedHalo halo;
  std::vector<int> needed;
  Eigen::MatrixX3d normals;  // #needed x 3
  std::int64_t joined_balls = 0;
};

// `owned_face_normals` (#Fl, optional): the normals of the rank's owned faces, already estimated
// (their serial bits); their balls are not run again.
NormalsNearSlab ii_normals_near_slab(const SlabSource& source, const DistributedSurface& surface,
                                     const IIParams& params, int columns,
                                     const Eigen::MatrixX3d* owned_face_normals = nullptr) {
  if (columns < 1)
    throw InputError("distributed II normals: at least 1 column beyond the slab, got " + std::to_string(columns));
  // The checks of ii_face_normals, on the whole box and the whole surface (same on every rank).
  const double h = source.h;
  Eigen::RowVector3d lo = Eigen::RowVector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::RowVector3d hi = -lo;
  for (Eigen::Index v = 0; v < surface.mesh.positions.rows(); ++v) {
    lo = lo.cwiseMin(surface.mesh.positions.row(v));
    hi = hi.cwiseMax(surface.mesh.positions.row(v));
  }
  MPI_Allreduce(MPI_IN_PLACE, lo.data(), 3, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, hi.data(), 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  const double across = (hi - lo).norm() / h;  // the serial object_across, from exact extremes
  const bool shrink = params.shrink_on_thin_parts;
  const IIStartRadius start = ii_start_radius(ii_digital_radius(h, params), across, shrink);
  const double rd = start.radius;
  ii_check_radius((source.upper - source.lower + Eigen::Vector3i::Ones()).maxCoeff(), rd);
  ii_check_radius_fits_object(across, rd);

  NormalsNearSlab out;
  // §7.2's retries use smaller balls than the first: the first's halo serves them all.
  out.halo = distributed_halo(source, surface, ii_halo_width(rd) + columns - 1);
  const DistributedHalo& halo = out.halo;

  // docs/math.md §7.1 over the whole grid: the components of the slab, joined over the ranks, and
  // the whole-grid component of each piece the halo's voxels hold.
  const RunComponents own = label_run_components(halo.grid, surface.slab.first, surface.slab.last);
  std::vector<std::int64_t> offset;
  const std::vector<std::int64_t> own_roots = global_components(own, surface, offset);
  const RunComponents pieces = label_run_components(halo.grid, halo.grid.lower().x(), halo.grid.upper().x());
  const std::vector<std::int64_t> piece_roots = halo_roots(pieces, own, own_roots, source, surface);
  std::unordered_map<std::int64_t, std::vector<int>> pieces_of;
  for (int p = 0; p < pieces.count; ++p) pieces_of[piece_roots[std::size_t(p)]].push_back(p);

  std::vector<int>& needed = out.needed;
  for (int f = 0; f < halo.mesh.num_faces(); ++f) {
    const int x = halo.mesh.surfels[std::size_t(f)].lower_voxel.x();
    if (x >= surface.slab.first - columns && x <= surface.slab.last + columns) needed.push_back(f);
  }

  // Two balls per face (docs/math.md §7.1: inner and outer voxel, seed = inner voxel), each the sum
  // over the pieces of the seed's component that reach its kernel cube: the moments of the listed
  // rows of `needed` at digital radius r, inner and outer per row; `joined_count`, if given, receives the
  // number of balls that took more than one piece.
  const auto side_moments = [&](double r, const std::vector<std::size_t>& rows, std::int64_t* joined_count = nullptr) {
    const int reach = int(std::ceil(r)) + 1;
    std::vector<IIBall> balls;
    std::vector<std::size_t> ball_begin;  // balls of (row i, side s): ball_begin[2 i + s] .. [2 i + s + 1]
    std::int64_t joined_balls = 0;
    for (std::size_t row : rows) {
      const Surfel& s = halo.mesh.surfels[std::size_t(needed[row])];
      const Eigen::Vector3i inner = s.inner_voxel();
      const int piece = pieces.label_at(inner);
      if (piece < 0) throw std::logic_error("distributed II normals: a surfel's inner voxel is not inside");
      for (const Eigen::Vector3i& centre : {inner, s.outer_voxel()}) {
        ball_begin.push_back(balls.size());
        balls.push_back({centre, inner});
        const Eigen::Vector3i cube_lower = centre - Eigen::Vector3i::Constant(reach);
        const Eigen::Vector3i cube_upper = centre + Eigen::Vector3i::Constant(reach);
        bool joined = false;
        for (int other : pieces_of[piece_roots[std::size_t(piece)]]) {
          if (other == piece) continue;
          const bool meets = (pieces.box_lower[std::size_t(other)].array() <= cube_upper.array()).all() &&
                             (pieces.box_upper[std::size_t(other)].array() >= cube_lower.array()).all();
          if (!meets) continue;
          balls.push_back({centre, pieces.representative[std::size_t(other)]});
          joined = true;
        }
        joined_balls += joined ? 1 : 0;
      }
    }
    ball_begin.push_back(balls.size());
    if (joined_count) *joined_count = joined_balls;
    const ComponentMoments moments = ii_component_moments(halo.grid, r, h, balls);
    std::vector<BallMoments> sides(2 * rows.size());
    for (std::size_t i = 0; i < sides.size(); ++i)
      for (std::size_t b = ball_begin[i]; b < ball_begin[i + 1]; ++b) add(sides[i], moments[b]);
    return sides;
  };

  // The trivial normals around a needed face come from faces within one column of it, which the
  // halo holds (it is at least 3 columns wide), and they are sums of integer vectors: the serial bits.
  const auto rows = Eigen::Index(needed.size());
  Eigen::MatrixX3d trivial(rows, 3), around = Eigen::MatrixX3d::Zero(rows, 3);
  const Eigen::MatrixX3d around_halo = shrink ? ii_trivial_normals_around(halo.mesh) : Eigen::MatrixX3d();
  for (Eigen::Index i = 0; i < rows; ++i) {
    trivial.row(i) = halo.mesh.surfels[std::size_t(needed[std::size_t(i)])].trivial_normal().transpose();
    if (shrink) around.row(i) = around_halo.row(needed[std::size_t(i)]);
  }
  // The rows whose normal is known: the owned faces, when given (final normals, retries included).
  std::vector<int> known_row(std::size_t(halo.mesh.num_faces()), -1);
  if (owned_face_normals) {
    if (owned_face_normals->rows() != surface.mesh.num_faces())
      throw InputError("distributed II normals: expected one known normal per owned face");
    for (int f = 0; f < surface.mesh.num_faces(); ++f) known_row[std::size_t(halo.owned_faces[std::size_t(f)])] = f;
  }
  std::vector<std::size_t> unknown;
  for (std::size_t i = 0; i < needed.size(); ++i)
    if (known_row[std::size_t(needed[i])] < 0) unknown.push_back(i);
  const std::vector<BallMoments> first = side_moments(rd, unknown, &out.joined_balls);
  Eigen::MatrixX3d& normals = out.normals;
  normals.resize(rows, 3);
  std::vector<std::uint8_t> ambiguous(needed.size(), 0);
  for (std::size_t i = 0; i < needed.size(); ++i)
    if (const int f = known_row[std::size_t(needed[i])]; f >= 0)
      normals.row(Eigen::Index(i)) = owned_face_normals->row(f);
  for (std::size_t k = 0; k < unknown.size(); ++k) {
    const std::size_t i = unknown[k];
    const IIFaceEstimate e =
        ii_estimate_from_moments(first[2 * k], first[2 * k + 1], trivial.row(Eigen::Index(i)).transpose(),
                                 around.row(Eigen::Index(i)).transpose());
    normals.row(Eigen::Index(i)) = e.normal.transpose();
    ambiguous[i] = e.ambiguous ? 1 : 0;
  }
  if (shrink) ii_retry_thin_parts(start, trivial, around, ambiguous, normals, side_moments);
  return out;
}

}  // namespace

int ii_halo_width(double digital_radius) { return int(std::ceil(digital_radius)) + 2; }

DistributedNormals distributed_ii_normals(const SlabSource& source, const DistributedSurface& surface,
                                          const IIParams& params) {
  // The owned faces and those one column beyond, which share the owned vertices (a vertex's faces
  // have lower voxels in the columns x - 1 and x of its pointel).
  const NormalsNearSlab near = ii_normals_near_slab(source, surface, params, 1);
  const DistributedHalo& halo = near.halo;
  const Eigen::MatrixX3d& normals = near.normals;
  std::vector<int> row_of(std::size_t(halo.mesh.num_faces()), -1);
  Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor> faces(Eigen::Index(near.needed.size()), 4);
  for (std::size_t i = 0; i < near.needed.size(); ++i) {
    row_of[std::size_t(near.needed[i])] = int(i);
    faces.row(Eigen::Index(i)) = halo.mesh.faces.row(near.needed[i]);
  }
  DistributedNormals out;
  out.halo_width = halo.width;
  out.joined_balls = near.joined_balls;

  // Owned faces, and owned vertices: the serial normalized sum, whose terms (the faces of a vertex)
  // come in serial face order here too.
  const int F = surface.mesh.num_faces();
  out.face_normals.resize(F, 3);
  for (int f = 0; f < F; ++f)
    out.face_normals.row(f) = normals.row(row_of[std::size_t(halo.owned_faces[std::size_t(f)])]);
  const Eigen::MatrixX3d vertex = vertex_normals_from_face_normals(normals, faces, halo.mesh.num_vertices());
  std::vector<int> halo_vertex(std::size_t(surface.mesh.num_vertices()), -1);
  for (int f = 0; f < F; ++f)
    for (int c = 0; c < 4; ++c)
      halo_vertex[std::size_t(surface.mesh.faces(f, c))] = halo.mesh.faces(halo.owned_faces[std::size_t(f)], c);
  out.vertex_normals.resize(surface.num_owned, 3);
  for (int v = 0; v < surface.num_owned; ++v) out.vertex_normals.row(v) = vertex.row(halo_vertex[std::size_t(v)]);
  return out;
}

NearSlabNormals distributed_ii_normals_near_slab(const SlabSource& source, const DistributedSurface& surface,
                                                 const IIParams& params, int columns,
                                                 const Eigen::MatrixX3d* owned_face_normals) {
  const NormalsNearSlab near = ii_normals_near_slab(source, surface, params, columns, owned_face_normals);
  const DistributedHalo& halo = near.halo;
  NearSlabNormals out;
  out.columns = columns;
  // The needed faces keep the halo's (serial) order; their vertices are renumbered by first
  // appearance, as extract_surface numbers them.
  const int F = int(near.needed.size());
  std::vector<int> local(std::size_t(halo.mesh.num_vertices()), -1);
  out.mesh.h = halo.mesh.h;
  out.mesh.faces.resize(F, 4);
  out.mesh.surfels.reserve(std::size_t(F));
  for (int f = 0; f < F; ++f) {
    const int g = near.needed[std::size_t(f)];
    out.mesh.surfels.push_back(halo.mesh.surfels[std::size_t(g)]);
    out.face_ids.push_back(halo.face_ids[std::size_t(g)]);
    for (int c = 0; c < 4; ++c) {
      int& l = local[std::size_t(halo.mesh.faces(g, c))];
      if (l < 0) {
        l = int(out.pointels.size());
        out.pointels.push_back(halo.pointels[std::size_t(halo.mesh.faces(g, c))]);
      }
      out.mesh.faces(f, c) = l;
    }
  }
  const int V = int(out.pointels.size());
  out.mesh.positions.resize(V, 3);
  for (int v = 0; v < V; ++v)
    for (int a = 0; a < 3; ++a)
      out.mesh.positions(v, a) = pointel_coordinate(out.pointels[std::size_t(v)][a], source.h);
  out.face_normals = near.normals;
  set_vertex_normals_from_faces(out);
  // The owned vertices through their owned faces, which lie within one column of the slab.
  std::vector<int> face_of_halo(std::size_t(halo.mesh.num_faces()), -1);
  for (int f = 0; f < F; ++f) face_of_halo[std::size_t(near.needed[std::size_t(f)])] = f;
  out.owned_vertices.assign(std::size_t(surface.num_owned), -1);
  for (std::size_t f = 0; f < halo.owned_faces.size(); ++f) {
    const int here = face_of_halo[std::size_t(halo.owned_faces[f])];
    for (int c = 0; c < 4; ++c) {
      const int v = surface.mesh.faces(Eigen::Index(f), c);
      if (v < surface.num_owned) out.owned_vertices[std::size_t(v)] = out.mesh.faces(here, c);
    }
  }
  return out;
}

}  // namespace corrlap
