#include "distributed_quality.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <vector>

#include "detail/exchange.hpp"
#include "detail/owned_vectors.hpp"
#include "distributed_curvature.hpp"
#include "distributed_mesh_output.hpp"
#include "near_slab.hpp"

namespace corrlap {

namespace {

using detail::all_to_all;
using detail::displacements;
using detail::gather_everywhere;
using detail::global_sum;

// The positions of the corners of the faces `wanted` (serial face ids), from the ranks that own
// those faces: 12 values per face (corner by corner, x y z).
std::vector<double> face_corners(const DistributedSurface& s, const Eigen::MatrixX3d& positions,
                                 const std::vector<std::int64_t>& wanted) {
  // Which rank owns which face ids: every rank's runs of consecutive ids (a few per rank).
  std::vector<std::int64_t> runs;
  for (std::size_t f = 0; f < s.face_ids.size(); ++f)
    if (f > 0 && s.face_ids[f] == s.face_ids[f - 1] + 1)
      ++runs.back();
    else
      runs.insert(runs.end(), {s.face_ids[f], 1});
  std::vector<int> counts;
  const std::vector<std::int64_t> all = gather_everywhere(runs, counts);
  struct OwnedRun {
    std::int64_t first, count;
    int rank;
  };
  std::vector<OwnedRun> owned;
  for (int r = 0, at = 0; r < s.ranks; at += counts[std::size_t(r)], ++r)
    for (int k = at; k < at + counts[std::size_t(r)]; k += 2)
      owned.push_back({all[std::size_t(k)], all[std::size_t(k) + 1], r});
  std::sort(owned.begin(), owned.end(), [](const OwnedRun& a, const OwnedRun& b) { return a.first < b.first; });
  const auto owner = [&](std::int64_t id) {
    auto it = std::upper_bound(owned.begin(), owned.end(), id,
                               [](std::int64_t x, const OwnedRun& run) { return x < run.first; });
    if (it == owned.begin() || id >= std::prev(it)->first + std::prev(it)->count)
      throw InputError("distributed quality: face " + std::to_string(id) + " has no owner");
    return std::prev(it)->rank;
  };

  // Ask the owners, face by face in the order wanted.
  std::vector<std::vector<std::int64_t>> asks(std::size_t(s.ranks));
  std::vector<std::vector<std::size_t>> asked_by(std::size_t(s.ranks));  // the index in `wanted` of each ask
  for (std::size_t i = 0; i < wanted.size(); ++i) {
    const auto r = std::size_t(owner(wanted[i]));
    asks[r].push_back(wanted[i]);
    asked_by[r].push_back(i);
  }
  std::vector<std::size_t> order;  // in send order: owner after owner
  for (const auto& indices : asked_by) order.insert(order.end(), indices.begin(), indices.end());
  std::vector<int> ask_counts(std::size_t(s.ranks)), asked_counts;
  for (int r = 0; r < s.ranks; ++r) ask_counts[std::size_t(r)] = int(asks[std::size_t(r)].size());
  const std::vector<std::int64_t> asked = all_to_all(asks, asked_counts);
  const Eigen::MatrixXd local = local_rows(s, positions);
  std::vector<double> answers;
  answers.reserve(12 * asked.size());
  for (std::int64_t id : asked) {
    const auto it = std::lower_bound(s.face_ids.begin(), s.face_ids.end(), id);
    const int f = int(it - s.face_ids.begin());
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 3; ++k) answers.push_back(local(s.mesh.faces(f, c), k));
  }
  std::vector<int> answer_counts(asked_counts), reply_counts(ask_counts);
  for (int& c : answer_counts) c *= 12;
  for (int& c : reply_counts) c *= 12;
  const std::vector<double> replies = all_to_all(answers, answer_counts, reply_counts);
  std::vector<double> corners(12 * wanted.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    std::copy_n(replies.begin() + std::ptrdiff_t(12 * k), 12, corners.begin() + std::ptrdiff_t(12 * order[k]));
  return corners;
}

// A sampling spacing below two edges: mean_curvature_at_sites then walks every vertex, as
// mean_curvature_at_vertices does.
double every_vertex_spacing(double h) { return 1e-6 * h; }

}  // namespace

double distributed_surface_area(const DistributedSurface& s, const Eigen::MatrixX3d& positions) {
  SurfelMesh mesh;
  mesh.faces = s.mesh.faces;
  mesh.positions = local_rows(s, positions);
  return global_sum(surface_area(mesh));
}

SolutionCheck distributed_check_solution(const DistributedSurface& s, const Eigen::MatrixX3d& before,
                                         const Eigen::MatrixX3d& after, std::optional<double> residual,
                                         const std::string& what) {
  if (before.rows() != s.num_owned || after.rows() != s.num_owned)
    throw InputError(what + ": expected one position per owned vertex");
  std::int64_t bad = std::numeric_limits<std::int64_t>::max();
  for (int v = 0; v < s.num_owned; ++v)
    if (!after.row(v).allFinite()) bad = std::min(bad, s.vertex_ids[std::size_t(v)]);
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
  if (bad != std::numeric_limits<std::int64_t>::max())
    throw NumericalError(what + ": the position of vertex " + std::to_string(bad) +
                         " is not finite; the solve broke down (check alpha0 and the normals)");
  SolutionCheck c;
  c.residual = residual;
  const double area_before = distributed_surface_area(s, before);
  const double area_after = distributed_surface_area(s, after);
  c.area_ratio = area_before > 0.0 ? area_after / area_before : 1.0;
  // The bounding boxes: minima as maxima of the negated coordinates.
  double extremes[12];
  for (int k = 0; k < 3; ++k) {
    const bool any = s.num_owned > 0;
    const double inf = std::numeric_limits<double>::infinity();
    extremes[k] = any ? before.col(k).maxCoeff() : -inf;
    extremes[3 + k] = any ? -before.col(k).minCoeff() : -inf;
    extremes[6 + k] = any ? after.col(k).maxCoeff() : -inf;
    extremes[9 + k] = any ? -after.col(k).minCoeff() : -inf;
  }
  MPI_Allreduce(MPI_IN_PLACE, extremes, 12, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  c.extent_ratio = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double side_before = extremes[k] + extremes[3 + k], side_after = extremes[6 + k] + extremes[9 + k];
    if (side_before > 0.0) c.extent_ratio = std::min(c.extent_ratio, side_after / side_before);
  }
  if (!std::isfinite(c.extent_ratio)) c.extent_ratio = 1.0;
  return judge_solution(c, what);
}

int distributed_components(const DistributedSurface& s) {
  // Components of this rank's faces over its local vertices (union-find).
  const Eigen::Index nl = s.mesh.num_vertices();
  std::vector<int> parent(static_cast<std::size_t>(nl));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int v) {
    while (parent[std::size_t(v)] != v) v = parent[std::size_t(v)] = parent[std::size_t(parent[std::size_t(v)])];
    return v;
  };
  for (int f = 0; f < s.mesh.num_faces(); ++f)
    for (int c = 1; c < 4; ++c) {
      const int a = find(s.mesh.faces(f, 0)), b = find(s.mesh.faces(f, c));
      if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    }
  std::vector<int> label(static_cast<std::size_t>(nl), -1);
  int pieces = 0;
  for (int v = 0; v < nl; ++v)
    if (find(v) == v) label[std::size_t(v)] = pieces++;
  for (int v = 0; v < nl; ++v) label[std::size_t(v)] = label[std::size_t(find(v))];

  // Global labels: this rank's pieces after the lower ranks'.
  std::int64_t first = pieces;
  MPI_Exscan(MPI_IN_PLACE, &first, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  if (s.rank == 0) first = 0;
  std::int64_t total = pieces;
  MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);

  // A vertex held by several ranks joins their pieces. Such vertices lie on the planes between
  // slabs: this rank's other vertices, and the owned ones that other ranks hold (the owners learn
  // which by summing a mark from every holder). Their rows and labels go to rank 0.
  Eigen::MatrixXd held = Eigen::MatrixXd::Zero(nl, 1);
  held.bottomRows(nl - s.num_owned).setOnes();
  const Eigen::MatrixXd holders = sum_at_owners(s, held);
  std::vector<std::int64_t> shared;
  for (Eigen::Index v = 0; v < nl; ++v)
    if (v >= s.num_owned || holders(v, 0) > 0.0)
      shared.insert(shared.end(), {s.rows[std::size_t(v)], first + label[std::size_t(v)]});

  // Rank 0 joins the pieces that share a row.
  int count = int(shared.size());
  std::vector<int> counts(std::size_t(s.ranks));
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::vector<std::int64_t> all(s.rank == 0 ? std::size_t(std::accumulate(counts.begin(), counts.end(), 0)) : 0);
  MPI_Gatherv(shared.data(), count, MPI_INT64_T, all.data(), counts.data(), displacements(counts).data(), MPI_INT64_T,
              0, MPI_COMM_WORLD);
  std::int64_t components = 0;
  if (s.rank == 0) {
    std::vector<std::int64_t> up(static_cast<std::size_t>(total));
    std::iota(up.begin(), up.end(), std::int64_t(0));
    const auto root = [&](std::int64_t x) {
      while (up[std::size_t(x)] != x) x = up[std::size_t(x)] = up[std::size_t(up[std::size_t(x)])];
      return x;
    };
    std::unordered_map<std::int64_t, std::int64_t> first_label;  // row -> a label holding it
    components = total;
    for (std::size_t k = 0; k + 1 < all.size(); k += 2) {
      const auto [it, added] = first_label.try_emplace(all[k], all[k + 1]);
      if (added) continue;
      const std::int64_t a = root(it->second), b = root(all[k + 1]);
      if (a == b) continue;
      up[std::size_t(std::max(a, b))] = std::min(a, b);
      --components;
    }
  }
  MPI_Bcast(&components, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  return int(components);
}

int quality_halo_columns(double r, double displacement, double h) {
  if (!(displacement >= 0.0) || !std::isfinite(displacement))
    throw InputError("distributed quality: the displacement must be a finite number >= 0");
  // A ball of radius r about a moved vertex holds moved faces whose staircase corners lie within
  // r + 2 displacement of the vertex's staircase position.
  return curvature_halo_columns(r + 2.0 * displacement, every_vertex_spacing(h), h);
}

SurfaceQuality distributed_measure_against_shape(const DistributedSurface& s, const DistributedHalo& halo,
                                                 const Eigen::MatrixX3d& positions, double displacement,
                                                 const ImplicitShape& shape, double r) {
  if (positions.rows() != s.num_owned) throw InputError("distributed quality: expected one position per owned vertex");
  const double h = s.mesh.h;
  const int needed = quality_halo_columns(r, displacement, h);
  if (halo.width < needed)
    throw InputError("distributed quality: the halo spans " + std::to_string(halo.width) + " columns, " +
                     std::to_string(needed) + " are needed");
  // The halo's faces at the given positions, from the ranks that own them.
  NearSlabNormals near;
  near.columns = halo.width;
  near.mesh = halo.mesh;
  near.face_ids = halo.face_ids;
  near.pointels = halo.pointels;
  const std::vector<double> corners = face_corners(s, positions, halo.face_ids);
  for (int f = 0; f < near.mesh.num_faces(); ++f)
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 3; ++k)
        near.mesh.positions(near.mesh.faces(f, c), k) =
            corners[12 * std::size_t(f) + 3 * std::size_t(c) + std::size_t(k)];
  near.face_normals = near.mesh.face_normals_from_positions();
  set_vertex_normals_from_faces(near);
  std::unordered_map<std::int64_t, int> here;  // serial id -> halo vertex
  for (std::size_t v = 0; v < halo.vertex_ids.size(); ++v)
    if (halo.vertex_ids[v] >= 0) here.emplace(halo.vertex_ids[v], int(v));
  near.owned_vertices.resize(std::size_t(s.num_owned));
  for (int v = 0; v < s.num_owned; ++v) near.owned_vertices[std::size_t(v)] = here.at(s.vertex_ids[std::size_t(v)]);

  const Eigen::VectorXd H = distributed_mean_curvature(s, near, r, every_vertex_spacing(h));
  Eigen::MatrixX3d normals(s.num_owned, 3);
  for (int v = 0; v < s.num_owned; ++v) normals.row(v) = near.vertex_normals.row(near.owned_vertices[std::size_t(v)]);
  SurfelMesh owned;
  owned.positions = positions;
  const Eigen::MatrixX3d truth = true_vertex_normals(shape, owned);
  double angles = 0.0;
  for (int v = 0; v < s.num_owned; ++v) angles += std::acos(std::clamp(normals.row(v).dot(truth.row(v)), -1.0, 1.0));
  const double n = double(std::max<std::int64_t>(s.num_vertices, 1));
  SurfaceQuality q;
  q.distance_l1 = global_sum(distances_to_surface(shape, positions).sum()) / n;
  q.normal_angle_deg = global_sum(angles) / n * 180.0 / std::numbers::pi;
  q.mean_curvature_error = global_sum((H - true_mean_curvatures(shape, positions)).cwiseAbs().sum()) / n;
  return q;
}

}  // namespace corrlap
