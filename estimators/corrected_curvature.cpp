#include "corrected_curvature.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/normal_fields.hpp>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <string>

namespace corrlap {

namespace {
using V3 = Eigen::Vector3d;

// docs/math.md §8.1, triangle (a, b, c) with normals (ua, ub, uc); uM = mean normal, not normalized.
struct TriangleMeasures {
  double mu0 = 0, mu1 = 0, mu2 = 0;
  Eigen::Matrix3d muxy = Eigen::Matrix3d::Zero();
};

void add_triangle(const V3& a, const V3& b, const V3& c, const V3& ua, const V3& ub, const V3& uc,
                  TriangleMeasures& m) {
  const V3 uM = (ua + ub + uc) / 3.0;
  m.mu0 += 0.5 * (b - a).cross(c - a).dot(uM);
  m.mu1 += 0.5 * (uM.cross(uc - ub).dot(a) + uM.cross(ua - uc).dot(b) + uM.cross(ub - ua).dot(c));
  m.mu2 += 0.5 * ua.cross(ub).dot(uc);
  const V3 dc = uc - ua, db = ub - ua;
  for (int i = 0; i < 3; ++i) {
    const V3 ei = V3::Unit(i);
    const double p = uM.dot(ei.cross(b - a)), q = uM.dot(ei.cross(c - a));
    for (int j = 0; j < 3; ++j) m.muxy(i, j) += 0.5 * (dc[j] * p - db[j] * q);
  }
}

double inclusion_ratio(double d_min, double d_max, double r) {
  // docs/math.md §8.3: 1 inside, 0 outside, linear in between.
  if (d_max <= r) return 1.0;
  if (r <= d_min) return 0.0;
  return (r - d_min) / (d_max - d_min);
}

// The faces as mean_curvature_at_vertices reads them: row-major, a face in one cache line.
struct WalkFace {
  V3 centroid;
  double rho;  // largest corner distance from the centroid
  double mu0, mu1;
  std::array<int, 4> corners;
};

// Edge-connected pieces of the faces whose centroids share a cube of the given side: their summed
// measures, a centre and a radius bounding every corner, and the faces around them, CSR.
struct FaceClusters {
  std::vector<int> of_face;
  std::vector<double> mu0, mu1, radius;
  std::vector<V3> centre;
  std::vector<int> around_start, around;
};

FaceClusters cluster_faces(const std::vector<WalkFace>& face, const std::vector<int>& neighbour_start,
                           const std::vector<int>& neighbour_faces, double side) {
  const std::size_t F = face.size();
  std::vector<std::array<std::int64_t, 3>> cube(F);
  for (std::size_t f = 0; f < F; ++f)
    for (int j = 0; j < 3; ++j) cube[f][std::size_t(j)] = std::int64_t(std::floor(face[f].centroid[j] / side));
  // Union-find over edge-adjacent faces in the same cube.
  std::vector<int> parent(F);
  for (std::size_t f = 0; f < F; ++f) parent[f] = int(f);
  const auto root = [&](int f) {
    while (parent[std::size_t(f)] != f) f = parent[std::size_t(f)] = parent[std::size_t(parent[std::size_t(f)])];
    return f;
  };
  for (std::size_t f = 0; f < F; ++f) {
    for (int i = neighbour_start[f]; i < neighbour_start[f + 1]; ++i) {
      const int n = neighbour_faces[std::size_t(i)];
      if (cube[std::size_t(n)] != cube[f]) continue;
      const int a = root(int(f)), b = root(n);
      if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
    }
  }
  FaceClusters c;
  c.of_face.assign(F, -1);
  std::vector<int> id_of_root(F, -1);
  for (std::size_t f = 0; f < F; ++f) {
    int& id = id_of_root[std::size_t(root(int(f)))];
    if (id < 0) id = int(c.mu0.size()), c.mu0.push_back(0.0), c.mu1.push_back(0.0), c.centre.push_back(V3::Zero());
    c.of_face[f] = id;
  }
  const std::size_t C = c.mu0.size();
  std::vector<int> count(C, 0);
  for (std::size_t f = 0; f < F; ++f) {
    const auto k = std::size_t(c.of_face[f]);
    c.mu0[k] += face[f].mu0, c.mu1[k] += face[f].mu1, c.centre[k] += face[f].centroid, ++count[k];
  }
  for (std::size_t k = 0; k < C; ++k) c.centre[k] /= double(count[k]);
  c.radius.assign(C, 0.0);
  for (std::size_t f = 0; f < F; ++f) {
    const auto k = std::size_t(c.of_face[f]);
    c.radius[k] = std::max(c.radius[k], (face[f].centroid - c.centre[k]).norm() + face[f].rho);
  }
  // Faces around each cluster: neighbours of its faces in other clusters, without repeats.
  std::vector<std::pair<int, int>> around;  // (cluster, face)
  for (std::size_t f = 0; f < F; ++f)
    for (int i = neighbour_start[f]; i < neighbour_start[f + 1]; ++i)
      if (const int n = neighbour_faces[std::size_t(i)]; c.of_face[std::size_t(n)] != c.of_face[f])
        around.emplace_back(c.of_face[f], n);
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  c.around_start.assign(C + 1, 0);
  c.around.reserve(around.size());
  for (const auto& [k, n] : around) ++c.around_start[std::size_t(k) + 1], c.around.push_back(n);
  for (std::size_t k = 0; k < C; ++k) c.around_start[k + 1] += c.around_start[k];
  return c;
}

// The rows of `points` (#points x 3) in Z-order (Morton order) of their cells of side `cell`:
// new -> old. Points near in space end up near in the order, so walks over neighbouring balls
// read the same cache lines.
// 21 bits -> every third bit of 63 (a Morton key's coordinate).
std::uint64_t morton_spread(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// Lattice coordinates anchored at the origin, shifted into the 21 bits of morton_spread.
constexpr std::int64_t kZOrderOffset = std::int64_t{1} << 20;

std::vector<int> z_order(const Eigen::MatrixX3d& points, double cell) {
  const Eigen::Index n = points.rows();
  std::vector<std::pair<std::uint64_t, int>> keyed(static_cast<std::size_t>(n));
  if (n == 0) return {};
  const Eigen::RowVector3d low = points.colwise().minCoeff();
  tbb::parallel_for(Eigen::Index(0), n, [&](Eigen::Index i) {
    std::uint64_t key = 0;
    for (int j = 0; j < 3; ++j) {
      const double c = std::floor((points(i, j) - low[j]) / cell);
      key |= morton_spread(std::uint64_t(std::clamp(c, 0.0, double(0x1fffff)))) << j;
    }
    keyed[std::size_t(i)] = {key, int(i)};
  });
  std::sort(keyed.begin(), keyed.end());
  std::vector<int> order(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = keyed[i].second;
  return order;
}

void check_mesh(const SurfelMesh& mesh) {
  if (mesh.num_faces() == 0) throw InputError("curvature: the mesh has no face");
  mesh.validate("curvature mesh");
}
}  // namespace

void CorrectedCurvature::build_adjacency() {
  const int F = int(faces_.rows()), V = int(positions_.rows());
  centroids_.resize(F, 3);
  for (int f = 0; f < F; ++f) {
    V3 c = V3::Zero();
    for (int k = 0; k < 4; ++k) c += positions_.row(faces_(f, k)).transpose();
    centroids_.row(f) = (c / 4.0).transpose();
  }
  // Edge-adjacent faces (sharing two consecutive corners), via sorted (min, max, face) records.
  struct Rec {
    int a, b, f, dir;
  };
  std::vector<Rec> recs;
  recs.reserve(std::size_t(4 * F));
  for (int f = 0; f < F; ++f)
    for (int k = 0; k < 4; ++k) {
      const int u = faces_(f, k), v = faces_(f, (k + 1) % 4);
      recs.push_back({std::min(u, v), std::max(u, v), f, u < v ? 1 : -1});
    }
  std::sort(recs.begin(), recs.end(),
            [](const Rec& x, const Rec& y) { return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.f < y.f); });
  std::vector<std::vector<int>> face_neighbours(static_cast<std::size_t>(F));
  face_left_edges_.assign(std::size_t(F), {});
  std::vector<std::array<int, 2>> edges;
  std::vector<double> emu1;
  std::vector<Eigen::Matrix3d> emuxy;
  for (std::size_t i = 0; i < recs.size();) {
    std::size_t j = i;
    while (j < recs.size() && recs[j].a == recs[i].a && recs[j].b == recs[i].b) ++j;
    for (std::size_t p = i; p < j; ++p)
      for (std::size_t q = i; q < j; ++q)
        if (p != q) face_neighbours[std::size_t(recs[p].f)].push_back(recs[q].f);
    if (!interpolated_) {
      // Constant normals: mu1 lives on the edge (a < b), between its left face (a -> b) and right face.
      int left = -1, right = -1, nl = 0, nr = 0;
      for (std::size_t p = i; p < j; ++p) {
        if (recs[p].dir > 0)
          left = recs[p].f, ++nl;
        else
          right = recs[p].f, ++nr;
      }
      double m = 0.0;
      Eigen::Matrix3d mxy = Eigen::Matrix3d::Zero();
      if (nl == 1 && nr == 1) {
        // Dihedral edge measures of the reference (CorrectedNormalCurrentFormula, constant u):
        // psi = angle between the right and left normals, e1 = unit(ur x ul).
        const V3 e = positions_.row(recs[i].b) - positions_.row(recs[i].a);
        const V3 ur = face_normals_.row(right), ul = face_normals_.row(left);
        V3 e1 = ur.cross(ul);
        const double l1 = std::min(e1.norm(), 1.0);
        if (l1 >= 1e-10) {
          e1 /= l1;
          const double psi = std::asin(l1);
          m = -psi * e.dot(e1);
          const double s1 = std::sin(psi), s2 = std::sin(2.0 * psi);
          const V3 e_ur = e.cross(ur), e1_ur = e1.cross(ur), e_e1_ur = e.cross(e1_ur);
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              mxy(a, b) =
                  -0.5 * ((-psi - 0.5 * s2) * e_ur[a] * e1_ur[b] + s1 * s1 * (e_ur[a] * ur[b] - e_e1_ur[a] * e1_ur[b]) +
                          (psi - 0.5 * s2) * e_e1_ur[a] * ur[b]);
        }
      }
      emuxy.push_back(mxy);
      if (left >= 0) face_left_edges_[std::size_t(left)].push_back(int(edges.size()));
      edges.push_back({recs[i].a, recs[i].b});
      emu1.push_back(m);
    }
    i = j;
  }
  neighbour_start_.assign(std::size_t(F) + 1, 0);
  neighbour_faces_.clear();
  for (int f = 0; f < F; ++f) {
    auto& n = face_neighbours[std::size_t(f)];
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    neighbour_faces_.insert(neighbour_faces_.end(), n.begin(), n.end());
    neighbour_start_[std::size_t(f) + 1] = int(neighbour_faces_.size());
    std::vector<int>().swap(n);
  }
  edges_.resize(Eigen::Index(edges.size()), 2);
  edge_mu1_.resize(Eigen::Index(edges.size()));
  for (std::size_t e = 0; e < edges.size(); ++e) {
    edges_(Eigen::Index(e), 0) = edges[e][0];
    edges_(Eigen::Index(e), 1) = edges[e][1];
    edge_mu1_[Eigen::Index(e)] = emu1[e];
  }
  edge_muxy_ = std::move(emuxy);
  vertex_face_.assign(std::size_t(V), -1);
  for (int f = F - 1; f >= 0; --f)
    for (int k = 0; k < 4; ++k) vertex_face_[std::size_t(faces_(f, k))] = f;
  build_grid();
}

void CorrectedCurvature::build_grid() {
  const Eigen::Index F = centroids_.rows();
  double edge = 0;
  for (Eigen::Index f = 0; f < F; ++f) edge += (positions_.row(faces_(f, 1)) - positions_.row(faces_(f, 0))).norm();
  grid_cell_ = std::max(edge / double(F), 1e-12) * 2.0;
  const Eigen::Vector3d lo = centroids_.colwise().minCoeff().transpose(),
                        hi = centroids_.colwise().maxCoeff().transpose();
  grid_origin_ = lo;
  const Eigen::Vector3d ext = (hi - lo) / grid_cell_;
  for (int a = 0; a < 3; ++a) grid_dims_[a] = std::clamp(int(std::floor(ext[a])) + 1, 1, 4096);
  auto cell_of = [&](const V3& x) {
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(int(std::floor((x[a] - grid_origin_[a]) / grid_cell_)), 0, grid_dims_[a] - 1);
    return (std::size_t(c.z()) * std::size_t(grid_dims_.y()) + std::size_t(c.y())) * std::size_t(grid_dims_.x()) +
           std::size_t(c.x());
  };
  const std::size_t ncells = std::size_t(grid_dims_.prod());
  grid_start_.assign(ncells + 1, 0);
  std::vector<std::size_t> cell(static_cast<std::size_t>(F));
  for (Eigen::Index f = 0; f < F; ++f) {
    cell[std::size_t(f)] = cell_of(centroids_.row(f).transpose());
    ++grid_start_[cell[std::size_t(f)] + 1];
  }
  for (std::size_t i = 0; i < ncells; ++i) grid_start_[i + 1] += grid_start_[i];
  grid_faces_.resize(std::size_t(F));
  std::vector<int> fill(grid_start_.begin(), grid_start_.end() - 1);
  for (Eigen::Index f = 0; f < F; ++f) grid_faces_[std::size_t(fill[cell[std::size_t(f)]]++)] = int(f);
}

int CorrectedCurvature::nearest_face(const Eigen::Vector3d& x) const {
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a)
    c[a] = std::clamp(int(std::floor((x[a] - grid_origin_[a]) / grid_cell_)), 0, grid_dims_[a] - 1);
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  const int max_shell = grid_dims_.maxCoeff();
  for (int s = 0; s <= max_shell; ++s) {
    // Cells of the shell at Chebyshev distance s; stop once no closer face can exist beyond it.
    for (int dz = -s; dz <= s; ++dz)
      for (int dy = -s; dy <= s; ++dy)
        for (int dx = -s; dx <= s; ++dx) {
          if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != s) continue;
          const int X = c.x() + dx, Y = c.y() + dy, Z = c.z() + dz;
          if (X < 0 || Y < 0 || Z < 0 || X >= grid_dims_.x() || Y >= grid_dims_.y() || Z >= grid_dims_.z()) continue;
          const std::size_t cell =
              (std::size_t(Z) * std::size_t(grid_dims_.y()) + std::size_t(Y)) * std::size_t(grid_dims_.x()) +
              std::size_t(X);
          for (int i = grid_start_[cell]; i < grid_start_[cell + 1]; ++i) {
            const int f = grid_faces_[std::size_t(i)];
            const double d2 = (centroids_.row(f).transpose() - x).squaredNorm();
            if (d2 < best_d2) best_d2 = d2, best = f;
          }
        }
    // Unvisited cells are at least s * cell away from x (also when x lies outside the grid box:
    // projecting x onto the box does not increase distances to points of the box).
    if (best >= 0 && std::sqrt(best_d2) <= double(s) * grid_cell_) break;
  }
  return best;
}

CorrectedCurvature CorrectedCurvature::interpolated(const SurfelMesh& mesh, const Eigen::MatrixX3d& vertex_normals) {
  check_mesh(mesh);
  CorrectedCurvature c;
  c.interpolated_ = true;
  c.positions_ = mesh.positions;
  c.faces_ = mesh.faces;
  c.vertex_normals_ = vertex_normals;
  validate_normals(c.vertex_normals_, mesh.num_vertices(), "vertex normals");
  const int F = mesh.num_faces();
  c.mu0_.resize(F), c.mu1_.resize(F), c.mu2_.resize(F);
  c.muxy_.resize(std::size_t(F));
  c.face_normals_.resize(F, 3);
  tbb::parallel_for(0, F, [&](int f) {
    // docs/math.md §8.2: fan around the barycentre b with u_b = normalized sum of the corner normals.
    V3 b = V3::Zero(), ub = V3::Zero();
    for (int k = 0; k < 4; ++k) {
      b += c.positions_.row(mesh.faces(f, k)).transpose();
      ub += c.vertex_normals_.row(mesh.faces(f, k)).transpose();
    }
    b /= 4.0;
    const double l = ub.norm();
    if (l > 0) ub /= l;
    TriangleMeasures m;
    for (int k = 0; k < 4; ++k) {
      const int v0 = mesh.faces(f, k), v1 = mesh.faces(f, (k + 1) % 4);
      add_triangle(b, c.positions_.row(v0).transpose(), c.positions_.row(v1).transpose(), ub,
                   c.vertex_normals_.row(v0).transpose(), c.vertex_normals_.row(v1).transpose(), m);
    }
    c.mu0_[f] = m.mu0, c.mu1_[f] = m.mu1, c.mu2_[f] = m.mu2;
    c.muxy_[std::size_t(f)] = m.muxy;
    c.face_normals_.row(f) = ub.transpose();
  });
  c.build_adjacency();
  return c;
}

CorrectedCurvature CorrectedCurvature::constant(const SurfelMesh& mesh, const Eigen::MatrixX3d& face_normals) {
  check_mesh(mesh);
  CorrectedCurvature c;
  c.interpolated_ = false;
  c.positions_ = mesh.positions;
  c.faces_ = mesh.faces;
  c.face_normals_ = face_normals;
  validate_normals(c.face_normals_, mesh.num_faces(), "face normals");
  const int F = mesh.num_faces();
  c.mu0_.resize(F), c.mu1_ = Eigen::VectorXd::Zero(F), c.mu2_ = Eigen::VectorXd::Zero(F);
  c.muxy_.assign(std::size_t(F), Eigen::Matrix3d::Zero());
  for (int f = 0; f < F; ++f) {
    V3 b = V3::Zero();
    for (int k = 0; k < 4; ++k) b += c.positions_.row(mesh.faces(f, k)).transpose();
    b /= 4.0;
    const V3 u = c.face_normals_.row(f).transpose();
    double a = 0;
    for (int k = 0; k < 4; ++k) {
      const V3 x0 = c.positions_.row(mesh.faces(f, k)), x1 = c.positions_.row(mesh.faces(f, (k + 1) % 4));
      a += 0.5 * (x0 - b).cross(x1 - b).dot(u);
    }
    c.mu0_[f] = a;
  }
  c.build_adjacency();
  c.compute_vertex_mu2();
  // Vertex normals for vertex-centred balls: normalized sum of incident face normals (docs/math.md §1.5).
  c.vertex_normals_ = vertex_normals_from_face_normals(c.face_normals_, c.faces_, int(c.positions_.rows()));
  return c;
}

void CorrectedCurvature::compute_vertex_mu2() {
  // Constant normals: mu2 lives on vertices, the algebraic area of the spherical polygon of the
  // normals of the faces around the vertex, fanned around their mean (reference: 0 at
  // non-manifold vertices, i.e. when the faces cannot be ordered as an umbrella).
  const int V = int(positions_.rows()), F = int(faces_.rows());
  std::vector<std::vector<int>> vf(static_cast<std::size_t>(V));
  for (int f = 0; f < F; ++f)
    for (int k = 0; k < 4; ++k) vf[std::size_t(faces_(f, k))].push_back(f);
  vertex_mu2_ = Eigen::VectorXd::Zero(V);
  tbb::parallel_for(0, V, [&](int v) {
    std::vector<int> fs, prev, next;
    for (int f : vf[std::size_t(v)]) {
      int j = 0;
      while (j < 4 && faces_(f, j) != v) ++j;
      fs.push_back(f);
      prev.push_back(faces_(f, (j + 3) % 4));
      next.push_back(faces_(f, (j + 1) % 4));
    }
    const std::size_t n = fs.size();
    for (std::size_t i = 1; i < n; ++i) {
      std::size_t j = i;
      while (j < n && next[j] != prev[i - 1]) ++j;
      if (j == n) return;  // not an umbrella: measure 0
      std::swap(fs[i], fs[j]), std::swap(next[i], next[j]), std::swap(prev[i], prev[j]);
    }
    V3 avg = V3::Zero();
    for (int f : fs) avg += face_normals_.row(f).transpose();
    const double l = avg.norm();
    if (l < 1e-10) return;
    avg /= l;
    double mu2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const V3 a = avg, b = face_normals_.row(fs[i]), c = face_normals_.row(fs[(i + 1) % n]);
      // Signed area of the spherical triangle (a, b, c) (Van Oosterom & Strackee).
      mu2 += 2.0 * std::atan2(a.dot(b.cross(c)), 1.0 + a.dot(b) + b.dot(c) + c.dot(a));
    }
    vertex_mu2_[v] = mu2;
  });
}

Eigen::Vector3d CorrectedCurvature::totals() const {
  if (!interpolated_) return {mu0_.sum(), edge_mu1_.sum(), vertex_mu2_.sum()};
  return {mu0_.sum(), mu1_.sum(), mu2_.sum()};
}

std::vector<std::pair<int, double>> CorrectedCurvature::faces_in_ball(const Eigen::Vector3d& x, double r,
                                                                      int seed) const {
  std::vector<std::pair<int, double>> result;
  if (r < 1e-6) {  // docs/math.md §8.3
    result.emplace_back(seed, 1e-6);
    return result;
  }
  // Visited marks: one stamp per face and per thread, so a walk costs O(faces in the ball).
  thread_local std::vector<std::uint32_t> stamp;
  thread_local std::uint32_t generation = 0;
  if (stamp.size() != std::size_t(faces_.rows()) || ++generation == 0) {
    stamp.assign(std::size_t(faces_.rows()), 0);
    generation = 1;
  }
  stamp[std::size_t(seed)] = generation;
  std::vector<int> queue{seed};
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int f = queue[head];
    const V3 b = centroids_.row(f);
    double dmin = (b - x).norm(), dmax = dmin;
    for (int k = 0; k < 4; ++k) {
      const double d = (positions_.row(faces_(f, k)).transpose() - x).norm();
      dmin = std::min(dmin, d), dmax = std::max(dmax, d);
    }
    const double w = inclusion_ratio(dmin, dmax, r);
    if (w <= 0.0) continue;  // the walk does not expand from faces of weight 0
    result.emplace_back(f, w);
    for (int i = neighbour_start_[std::size_t(f)]; i < neighbour_start_[std::size_t(f) + 1]; ++i)
      if (const int n = neighbour_faces_[std::size_t(i)]; stamp[std::size_t(n)] != generation) {
        stamp[std::size_t(n)] = generation;
        queue.push_back(n);
      }
  }
  return result;
}

void CorrectedCurvature::estimate(const Eigen::Vector3d& x, double r, int seed, const Eigen::Vector3d& N,
                                  CurvatureEstimates& out, Eigen::Index i) const {
  const auto faces = faces_in_ball(x, r, seed);
  thread_local std::vector<std::uint32_t> vstamp;
  thread_local std::uint32_t vgeneration = 0;
  if (!interpolated_ && (vstamp.size() != std::size_t(positions_.rows()) || ++vgeneration == 0)) {
    vstamp.assign(std::size_t(positions_.rows()), 0);
    vgeneration = 1;
  }
  double m0 = 0, m1 = 0, m2 = 0;
  Eigen::Matrix3d mxy = Eigen::Matrix3d::Zero();
  for (const auto& [f, w] : faces) {
    m0 += w * mu0_[f];
    m1 += w * mu1_[f];
    m2 += w * mu2_[f];
    mxy += w * muxy_[std::size_t(f)];
    if (!interpolated_ && r >= 1e-6) {
      // Constant normals: edges (counted from their left face) and vertices of the faces met.
      for (int e : face_left_edges_[std::size_t(f)]) {
        const V3 a = positions_.row(edges_(e, 0)), b = positions_.row(edges_(e, 1));
        const double d0 = (a - x).norm(), d1 = (b - x).norm(), dm = (0.5 * (a + b) - x).norm();
        const double we = inclusion_ratio(std::min({d0, d1, dm}), std::max({d0, d1, dm}), r);
        m1 += we * edge_mu1_[e];
        mxy += we * edge_muxy_[std::size_t(e)];
      }
      for (int k = 0; k < 4; ++k) {
        const int v = faces_(f, k);
        if (vstamp[std::size_t(v)] == vgeneration) continue;
        vstamp[std::size_t(v)] = vgeneration;
        if ((positions_.row(v).transpose() - x).norm() <= r) m2 += vertex_mu2_[v];
      }
    }
  }
  out.area[i] = m0;
  // docs/math.md §8.3: H = mu1 / (2 mu0), G = mu2 / mu0 (0 if mu0 = 0).
  out.H[i] = m0 == 0.0 ? 0.0 : m1 / (2.0 * m0);
  out.G[i] = m0 == 0.0 ? 0.0 : m2 / m0;
  const Eigen::Matrix3d T = 0.5 * (mxy + mxy.transpose()) + 1000.0 * m0 * N * N.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(T);
  const double inv = m0 == 0.0 ? 0.0 : 1.0 / m0;
  out.k1[i] = -es.eigenvalues()[1] * inv;
  out.k2[i] = -es.eigenvalues()[0] * inv;
  out.d1.row(i) = es.eigenvectors().col(1).transpose();
  out.d2.row(i) = es.eigenvectors().col(0).transpose();
}

namespace {
void check_radius(double r, const Eigen::MatrixX3d& positions) {
  if (!(r >= 0.0) || !std::isfinite(r))
    throw InputError("curvature: ball radius must be >= 0, got " + std::to_string(r));
  const double diag = (positions.colwise().maxCoeff() - positions.colwise().minCoeff()).norm();
  if (r > 2.0 * diag)
    throw InputError("curvature: ball radius " + std::to_string(r) + " is larger than the mesh (diagonal " +
                     std::to_string(diag) + ")");
}
CurvatureEstimates make_estimates(Eigen::Index n) {
  CurvatureEstimates e;
  e.H.resize(n), e.G.resize(n), e.k1.resize(n), e.k2.resize(n), e.area.resize(n);
  e.d1.resize(n, 3), e.d2.resize(n, 3);
  return e;
}
}  // namespace

CurvatureEstimates CorrectedCurvature::at_faces(double r) const {
  check_radius(r, positions_);
  const Eigen::Index F = faces_.rows();
  CurvatureEstimates out = make_estimates(F);
  tbb::parallel_for(Eigen::Index(0), F, [&](Eigen::Index f) {
    estimate(centroids_.row(f).transpose(), r, int(f), face_normals_.row(f).transpose(), out, f);
  });
  return out;
}

CurvatureEstimates CorrectedCurvature::at_vertices(double r) const {
  check_radius(r, positions_);
  const Eigen::Index V = positions_.rows();
  CurvatureEstimates out = make_estimates(V);
  tbb::parallel_for(Eigen::Index(0), V, [&](Eigen::Index v) {
    const int seed = vertex_face_[std::size_t(v)];
    if (seed < 0) {
      out.H[v] = out.G[v] = out.k1[v] = out.k2[v] = out.area[v] = 0.0;
      out.d1.row(v).setZero(), out.d2.row(v).setZero();
      return;
    }
    // docs/math.md §8.3 (choice): ball at the vertex, seed = an incident face.
    estimate(positions_.row(v).transpose(), r, seed, vertex_normals_.row(v).transpose(), out, v);
  });
  return out;
}

CorrectedCurvature::MeanCurvature CorrectedCurvature::mean_curvature_at_vertices(double r) const {
  check_radius(r, positions_);
  if (!interpolated_ || r < 1e-6) {
    CurvatureEstimates e = at_vertices(r);
    return {std::move(e.H), std::move(e.area)};
  }
  const std::vector<int> vertex_order = z_order(positions_, grid_cell_);
  std::vector<int> every(vertex_order.size());
  std::iota(every.begin(), every.end(), 0);
  return walk_mean_curvature(r, vertex_order, every);
}

CorrectedCurvature::MeanCurvature CorrectedCurvature::walk_mean_curvature(double r,
                                                                          const std::vector<int>& vertex_order,
                                                                          const std::vector<int>& at) const {
  const Eigen::Index V = positions_.rows(), F = faces_.rows();
  // Row-major copies: a face's data in one or two cache lines (the Eigen members are column-major),
  // faces and vertices renumbered in Z-order (z_order): the walk's reads stay local. "Old" indices
  // are the mesh's, "new" the walk's.
  const double edge = 0.5 * grid_cell_;
  const std::vector<int> face_order = z_order(centroids_, 2.0 * edge);
  std::vector<int> face_rank(static_cast<std::size_t>(F)), vertex_rank(static_cast<std::size_t>(V));
  for (std::size_t i = 0; i < face_order.size(); ++i) face_rank[std::size_t(face_order[i])] = int(i);
  for (std::size_t i = 0; i < vertex_order.size(); ++i) vertex_rank[std::size_t(vertex_order[i])] = int(i);
  std::vector<WalkFace> face(static_cast<std::size_t>(F));
  std::vector<V3> position(static_cast<std::size_t>(V));
  for (Eigen::Index i = 0; i < V; ++i)
    position[std::size_t(i)] = positions_.row(vertex_order[std::size_t(i)]).transpose();
  std::vector<int> neighbour_start(static_cast<std::size_t>(F) + 1, 0), neighbour_faces(neighbour_faces_.size());
  for (Eigen::Index i = 0; i < F; ++i) {
    const auto f = std::size_t(face_order[std::size_t(i)]);
    neighbour_start[std::size_t(i) + 1] =
        neighbour_start[std::size_t(i)] + neighbour_start_[f + 1] - neighbour_start_[f];
  }
  tbb::parallel_for(Eigen::Index(0), F, [&](Eigen::Index i) {
    const int f = face_order[std::size_t(i)];
    WalkFace& d = face[std::size_t(i)];
    d.centroid = centroids_.row(f).transpose();
    d.rho = 0.0;
    for (int k = 0; k < 4; ++k) {
      d.corners[std::size_t(k)] = vertex_rank[std::size_t(faces_(f, k))];
      d.rho = std::max(d.rho, (position[std::size_t(d.corners[std::size_t(k)])] - d.centroid).norm());
    }
    d.mu0 = mu0_[f], d.mu1 = mu1_[f];
    int out = neighbour_start[std::size_t(i)];
    for (int j = neighbour_start_[std::size_t(f)]; j < neighbour_start_[std::size_t(f) + 1]; ++j)
      neighbour_faces[std::size_t(out++)] = face_rank[std::size_t(neighbour_faces_[std::size_t(j)])];
  });
  // Clusters pay off when the ball holds many of them (radius >= 12 edges, ~3 cluster widths);
  // below, the walk is face by face.
  const bool use_clusters = r >= 12.0 * edge;
  const FaceClusters clusters =
      use_clusters ? cluster_faces(face, neighbour_start, neighbour_faces, 4.0 * edge) : FaceClusters{};
  MeanCurvature out{Eigen::VectorXd::Zero(V), Eigen::VectorXd::Zero(V)};
  struct Walk {
    std::vector<std::uint32_t> stamp, cluster_seen;
    std::vector<char> cluster_inside;
    std::uint32_t generation = 0;
    std::vector<int> queue;
  };
  tbb::enumerable_thread_specific<Walk> walks;
  const std::size_t C = clusters.mu0.size();
  const auto walk = [&](const tbb::blocked_range<std::size_t>& range) {
    Walk& w = walks.local();
    if (w.stamp.empty()) {
      w.stamp.assign(std::size_t(F), 0);
      w.cluster_seen.assign(C, 0);
      w.cluster_inside.assign(C, 0);
    }
    for (std::size_t k = range.begin(); k != range.end(); ++k) {
      const std::size_t i = std::size_t(at[k]);
      const int v = vertex_order[i];
      if (vertex_face_[std::size_t(v)] < 0) {
        out.H[v] = out.area[v] = 0.0;
        continue;
      }
      const int seed = face_rank[std::size_t(vertex_face_[std::size_t(v)])];
      if (++w.generation == 0) {
        std::fill(w.stamp.begin(), w.stamp.end(), 0u);
        std::fill(w.cluster_seen.begin(), w.cluster_seen.end(), 0u);
        w.generation = 1;
      }
      // The walk of faces_in_ball (same faces, same weights), fused with the sums of estimate().
      // A cluster whose every corner is within r is summed at once (its faces all have weight 1
      // and are edge-connected, so the walk would reach them all) and the walk goes on from the
      // faces around it.
      const V3 x = position[std::size_t(i)];
      double m0 = 0.0, m1 = 0.0;
      w.queue.assign(1, seed);
      w.stamp[std::size_t(seed)] = w.generation;
      const auto push = [&w](int n) {
        if (w.stamp[std::size_t(n)] != w.generation) {
          w.stamp[std::size_t(n)] = w.generation;
          w.queue.push_back(n);
        }
      };
      // True when face f is summed with its whole cluster, now (first face of it popped) or before.
      const auto summed_with_cluster = [&](int f) {
        const std::size_t c = std::size_t(clusters.of_face[std::size_t(f)]);
        if (w.cluster_seen[c] == w.generation) return w.cluster_inside[c] != 0;
        w.cluster_seen[c] = w.generation;
        const double inner = r - clusters.radius[c];
        w.cluster_inside[c] = inner >= 0.0 && (clusters.centre[c] - x).squaredNorm() <= inner * inner;
        if (!w.cluster_inside[c]) return false;
        m0 += clusters.mu0[c];
        m1 += clusters.mu1[c];
        for (int i = clusters.around_start[c]; i < clusters.around_start[c + 1]; ++i)
          push(clusters.around[std::size_t(i)]);
        return true;
      };
      for (std::size_t head = 0; head < w.queue.size(); ++head) {
        const int f = w.queue[head];
        if (use_clusters && summed_with_cluster(f)) continue;
        const WalkFace& d = face[std::size_t(f)];
        // Squared distances: the tests against r -+ rho need no root, and dmin, dmax are the roots
        // of the least and largest squares (a root is monotonic: the same numbers as the norms).
        const double dc2 = (d.centroid - x).squaredNorm();
        const double inner = r - d.rho, outer = r + d.rho;
        double weight;
        if (inner >= 0.0 && dc2 <= inner * inner) {
          weight = 1.0;  // every corner within r: dmax <= r
        } else if (dc2 >= outer * outer) {
          continue;  // every corner at r or beyond: weight 0, the walk stops here
        } else {
          double least = dc2, largest = dc2;
          for (const int k : d.corners) {
            const double dk2 = (position[std::size_t(k)] - x).squaredNorm();
            least = std::min(least, dk2), largest = std::max(largest, dk2);
          }
          weight = inclusion_ratio(std::sqrt(least), std::sqrt(largest), r);
          if (weight <= 0.0) continue;
        }
        m0 += weight * d.mu0;
        m1 += weight * d.mu1;
        for (int j = neighbour_start[std::size_t(f)]; j < neighbour_start[std::size_t(f) + 1]; ++j)
          push(neighbour_faces[std::size_t(j)]);
      }
      out.area[v] = m0;
      out.H[v] = m0 == 0.0 ? 0.0 : m1 / (2.0 * m0);  // as estimate()
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, at.size(), 256), walk);
  return out;
}

namespace {
// Sites of mean_curvature_at_sites in a uniform grid of cells of side >= the query radius (the
// 27 cells around a point hold every site within it), each cell a linked list of its sites.
class SiteGrid {
 public:
  SiteGrid(const Eigen::MatrixX3d& points, double radius) {
    low_ = points.colwise().minCoeff().transpose();
    const V3 extent = points.colwise().maxCoeff().transpose() - low_;
    // At most 128 cells a side (a few MB of heads); more sites per cell below that.
    cell_ = std::max(radius, extent.maxCoeff() / 128.0);
    for (int j = 0; j < 3; ++j) dims_[j] = int(std::floor(extent[j] / cell_)) + 1;
    head_.assign(std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]), -1);
  }
  void add(int site, const V3& p) {
    const std::size_t c = index(cell_of(p));
    if (next_.size() <= std::size_t(site)) next_.resize(std::size_t(site) + 1, -1);
    next_[std::size_t(site)] = head_[c];
    head_[c] = site;
  }
  // Calls visit(site) for every site in the 27 cells around p; stops when visit returns true.
  template <class Visit>
  bool any_near(const V3& p, Visit&& visit) const {
    const Eigen::Vector3i c = cell_of(p);
    for (int z = std::max(c[2] - 1, 0); z <= std::min(c[2] + 1, dims_[2] - 1); ++z)
      for (int y = std::max(c[1] - 1, 0); y <= std::min(c[1] + 1, dims_[1] - 1); ++y)
        for (int x = std::max(c[0] - 1, 0); x <= std::min(c[0] + 1, dims_[0] - 1); ++x)
          for (int s = head_[index({x, y, z})]; s >= 0; s = next_[std::size_t(s)])
            if (visit(s)) return true;
    return false;
  }

 private:
  Eigen::Vector3i cell_of(const V3& p) const {
    Eigen::Vector3i c;
    for (int j = 0; j < 3; ++j) c[j] = std::clamp(int(std::floor((p[j] - low_[j]) / cell_)), 0, dims_[j] - 1);
    return c;
  }
  std::size_t index(const Eigen::Vector3i& c) const {
    return (std::size_t(c[2]) * std::size_t(dims_[1]) + std::size_t(c[1])) * std::size_t(dims_[0]) + std::size_t(c[0]);
  }
  V3 low_;
  double cell_ = 1.0;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<int> head_, next_;
};
}  // namespace

CorrectedCurvature::MeanCurvature CorrectedCurvature::mean_curvature_at_sites(double r, double spacing) const {
  return sites_mean_curvature(r, spacing, nullptr);
}

CorrectedCurvature::MeanCurvature CorrectedCurvature::mean_curvature_at_sites(double r, double spacing,
                                                                              const std::vector<int>& vertices) const {
  const Eigen::Index V = positions_.rows();
  for (int v : vertices)
    if (v < 0 || v >= V)
      throw InputError("curvature: vertex " + std::to_string(v) + " is not one of the mesh's " + std::to_string(V));
  return sites_mean_curvature(r, spacing, &vertices);
}

CorrectedCurvature::MeanCurvature CorrectedCurvature::sites_mean_curvature(double r, double spacing,
                                                                           const std::vector<int>* only) const {
  check_radius(r, positions_);
  if (!(spacing >= 0.0) || !std::isfinite(spacing))
    throw InputError("curvature: site spacing must be >= 0, got " + std::to_string(spacing));
  const Eigen::Index V = positions_.rows();
  // wanted[v]: v's H is asked for.
  std::vector<char> wanted(std::size_t(V), only ? 0 : 1);
  if (only)
    for (int v : *only) wanted[std::size_t(v)] = 1;
  const auto keep_wanted = [&](MeanCurvature m) {
    if (only)
      for (Eigen::Index v = 0; v < V; ++v)
        if (!wanted[std::size_t(v)]) m.H[v] = m.area[v] = 0.0;
    return m;
  };
  const double edge = 0.5 * grid_cell_;
  if (!interpolated_ || r < 1e-6) return keep_wanted(mean_curvature_at_vertices(r));
  const std::vector<int> vertex_order = z_order(positions_, grid_cell_);
  // The edge is a mean over the faces, whose last bits depend on which faces the mesh holds: a
  // spacing of exactly two edges (0.25 r at r = 8 h) would take either branch on two pieces of one
  // surface. The margin puts such round values on one side.
  if (spacing < 2.0 * edge * (1.0 - 1e-9)) {
    std::vector<int> at;
    for (std::size_t i = 0; i < vertex_order.size(); ++i)
      if (wanted[std::size_t(vertex_order[i])]) at.push_back(int(i));
    return walk_mean_curvature(r, vertex_order, at);
  }
  const double cover2 = 0.25 * spacing * spacing, reach2 = spacing * spacing, agree = 0.5;
  // Sites per cell of a lattice anchored at the origin (docs/math.md §8.4): the choice in a cell
  // depends on its vertices alone, so any part of the surface that holds a cell's vertices chooses
  // its sites the same (the distributed front end's slabs), and cells run in parallel. Cells of two
  // spacings: sites on either side of a border do not cover each other, so smaller cells add sites
  // to walk, and larger ones lengthen each vertex's cover test (bench/RESULTS.md).
  const double cell = 2.0 * spacing;
  // Ties of the Z-order (a lattice cell of grid_cell_ holds several vertices) go by position, not
  // by vertex index: another part of the mesh numbers its vertices otherwise. The index decides
  // only between copies of one point.
  struct Keyed {
    std::array<std::int64_t, 3> cell;
    std::uint64_t z;  // Z-order of the vertex in the lattice of side grid_cell_, anchored at the origin
    std::array<double, 3> p;
    int v;
    bool operator<(const Keyed& o) const {
      return cell != o.cell ? cell < o.cell : z != o.z ? z < o.z : p != o.p ? p < o.p : v < o.v;
    }
  };
  std::vector<Keyed> keyed;
  keyed.reserve(std::size_t(V));
  for (Eigen::Index v = 0; v < V; ++v) {
    if (vertex_face_[std::size_t(v)] < 0) continue;
    Keyed k{{}, 0, {positions_(v, 0), positions_(v, 1), positions_(v, 2)}, int(v)};
    for (int j = 0; j < 3; ++j) {
      k.cell[std::size_t(j)] = std::int64_t(std::floor(positions_(v, j) / cell));
      k.z |= morton_spread(std::uint64_t(std::int64_t(std::floor(positions_(v, j) / grid_cell_)) + kZOrderOffset)) << j;
    }
    keyed.push_back(k);
  }
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::size_t> run_begin;  // the vertices of each cell: keyed[run_begin[c] .. run_begin[c + 1])
  for (std::size_t i = 0; i < keyed.size(); ++i)
    if (i == 0 || keyed[i].cell != keyed[i - 1].cell) run_begin.push_back(i);
  run_begin.push_back(keyed.size());
  // In each cell, in Z-order: a vertex becomes a site unless a site of its cell within spacing / 2
  // has a normal within 60 degrees of its own.
  std::vector<std::vector<int>> cell_sites(run_begin.size() - 1);
  tbb::parallel_for(std::size_t(0), cell_sites.size(), [&](std::size_t c) {
    std::vector<int>& sites = cell_sites[c];
    for (std::size_t i = run_begin[c]; i < run_begin[c + 1]; ++i) {
      const int v = keyed[i].v;
      const V3 p = positions_.row(v).transpose(), n = vertex_normals_.row(v).transpose();
      const bool covered = std::any_of(sites.begin(), sites.end(), [&](int u) {
        return (positions_.row(u).transpose() - p).squaredNorm() <= cover2 && vertex_normals_.row(u).dot(n) >= agree;
      });
      if (!covered) sites.push_back(v);
    }
  });
  std::vector<int> vertex_rank(static_cast<std::size_t>(V));
  for (std::size_t i = 0; i < vertex_order.size(); ++i) vertex_rank[std::size_t(vertex_order[i])] = int(i);
  SiteGrid grid(positions_, spacing);
  std::vector<int> site_vertex;  // mesh index of each site
  for (const std::vector<int>& sites : cell_sites)
    for (int v : sites) {
      grid.add(int(site_vertex.size()), positions_.row(v).transpose());
      site_vertex.push_back(v);
    }
  // A site contributes to v when within `spacing` with a normal within 60 degrees.
  const auto contributes = [&](int u, const V3& p, const V3& n, double& d2) {
    d2 = (positions_.row(u).transpose() - p).squaredNorm();
    return d2 < reach2 && vertex_normals_.row(u).dot(n) >= agree;
  };
  // The sites to walk: all, or those contributing to a wanted vertex.
  std::vector<char> walk_site(site_vertex.size(), only ? 0 : 1);
  if (only)
    for (int v : *only) {
      if (vertex_face_[std::size_t(v)] < 0) continue;
      const V3 p = positions_.row(v).transpose(), n = vertex_normals_.row(v).transpose();
      grid.any_near(p, [&](int s) {
        double d2;
        if (contributes(site_vertex[std::size_t(s)], p, n, d2)) walk_site[std::size_t(s)] = 1;
        return false;
      });
    }
  std::vector<int> site_rank;  // Z-order ranks of the sites walked
  for (std::size_t s = 0; s < site_vertex.size(); ++s)
    if (walk_site[s]) site_rank.push_back(vertex_rank[std::size_t(site_vertex[s])]);
  const MeanCurvature walked = walk_mean_curvature(r, vertex_order, site_rank);
  MeanCurvature out{Eigen::VectorXd::Zero(V), Eigen::VectorXd::Zero(V)};
  tbb::parallel_for(Eigen::Index(0), V, [&](Eigen::Index v) {
    if (vertex_face_[std::size_t(v)] < 0 || !wanted[std::size_t(v)]) return;  // as at_vertices: 0
    const V3 p = positions_.row(v).transpose(), n = vertex_normals_.row(v).transpose();
    double weights = 0.0, H = 0.0, area = 0.0;
    grid.any_near(p, [&](int s) {
      const int u = site_vertex[std::size_t(s)];
      double d2;
      if (contributes(u, p, n, d2)) {
        const double t = 1.0 - d2 / reach2, weight = t * t;
        weights += weight, H += weight * walked.H[u], area += weight * walked.area[u];
      }
      return false;
    });
    // The covering site is within spacing / 2: weights >= (3/4)^2.
    out.H[v] = H / weights;
    out.area[v] = area / weights;
  });
  return out;
}

CurvatureEstimates CorrectedCurvature::at_points(const Eigen::MatrixX3d& points, double r) const {
  check_radius(r, positions_);
  const Eigen::Index P = points.rows();
  CurvatureEstimates out = make_estimates(P);
  tbb::parallel_for(Eigen::Index(0), P, [&](Eigen::Index i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    const int seed = nearest_face(x);
    estimate(x, r, seed, face_normals_.row(seed).transpose(), out, i);
  });
  return out;
}

}  // namespace corrlap
