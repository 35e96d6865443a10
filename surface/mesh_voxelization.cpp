#include "mesh_voxelization.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <numeric>
#include <sstream>

namespace corrlap {

namespace {

using Tri = std::array<int, 3>;

struct Crossing {
  double x;  // coordinate along the ray axis
  int sign;  // +1: the ray leaves the (outward-oriented) solid there, -1: it enters
  bool operator<(const Crossing& o) const { return x < o.x || (x == o.x && sign < o.sign); }
};

// 2D orientation of (u, v, p) in the (b, c) plane, with a symbolic perturbation of the query point
// p -> p + (eps, eps^2) resolving exact zeros (spec-independent robustness device, "simulation of
// simplicity"). Evaluated with the lower vertex id first so that the two triangles sharing an
// edge see exactly opposite values: the ray is counted in exactly one of them.
inline int edge_sign(const Eigen::MatrixX3d& P, int u, int v, int b, int c, double pb, double pc, double& value) {
  bool flip = false;
  if (u > v) {
    std::swap(u, v);
    flip = true;
  }
  const double ub = P(u, b), uc = P(u, c);
  const double db = P(v, b) - ub, dc = P(v, c) - uc;
  double e = db * (pc - uc) - dc * (pb - ub);
  int s = e > 0 ? 1 : (e < 0 ? -1 : 0);
  if (s == 0) {
    // d/dpb = -dc (first order in eps), d/dpc = db (second order)
    s = dc < 0 ? 1 : (dc > 0 ? -1 : (db > 0 ? 1 : (db < 0 ? -1 : 0)));
  }
  if (flip) {
    e = -e;
    s = -s;
  }
  value = e;
  return s;
}

struct Prepared {
  Eigen::MatrixX3d P;     // merged vertex positions
  std::vector<Tri> tris;  // non-degenerate triangles
};

Prepared prepare(const PolygonMesh& mesh, MeshVoxelizationReport& r) {
  const Eigen::Index nv = mesh.positions.rows();
  if (nv == 0 || mesh.faces.empty()) throw InputError("mesh voxelization: the mesh has no vertex or no face");
  for (Eigen::Index v = 0; v < nv; ++v)
    if (!mesh.positions.row(v).allFinite())
      throw InputError("mesh voxelization: vertex " + std::to_string(v) + " has a non-finite position");
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.faces[f].size() < 3)
      throw InputError("mesh voxelization: face " + std::to_string(f) + " has fewer than 3 corners");
    for (int id : mesh.faces[f])
      if (id < 0 || id >= nv)
        throw InputError("mesh voxelization: face " + std::to_string(f) + " refers to vertex " + std::to_string(id) +
                         " (mesh has " + std::to_string(nv) + ")");
  }
  r.input_vertices = int(nv);
  // Merge vertices with identical positions (triangle soups, STL-like files) so that shared edges
  // are recognised: the watertight edge rule needs one id per geometric vertex.
  std::vector<int> order(static_cast<std::size_t>(nv));
  std::iota(order.begin(), order.end(), 0);
  auto less = [&](int a, int b) {
    for (int c = 0; c < 3; ++c) {
      if (mesh.positions(a, c) < mesh.positions(b, c)) return true;
      if (mesh.positions(a, c) > mesh.positions(b, c)) return false;
    }
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<int> remap(static_cast<std::size_t>(nv));
  Prepared out;
  std::vector<int> rep;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || mesh.positions.row(order[i]) != mesh.positions.row(order[i - 1])) rep.push_back(order[i]);
    remap[std::size_t(order[i])] = int(rep.size()) - 1;
  }
  r.merged_vertices = int(nv) - int(rep.size());
  out.P.resize(Eigen::Index(rep.size()), 3);
  for (std::size_t i = 0; i < rep.size(); ++i) out.P.row(Eigen::Index(i)) = mesh.positions.row(rep[i]);

  const auto T = triangulate(mesh);
  r.triangles = int(T.rows());
  out.tris.reserve(std::size_t(T.rows()));
  for (Eigen::Index t = 0; t < T.rows(); ++t) {
    Tri tri{remap[std::size_t(T(t, 0))], remap[std::size_t(T(t, 1))], remap[std::size_t(T(t, 2))]};
    const Eigen::Vector3d a = out.P.row(tri[0]), b = out.P.row(tri[1]), c = out.P.row(tri[2]);
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || (b - a).cross(c - a).squaredNorm() == 0.0) {
      ++r.degenerate_triangles;  // contributes no crossing; its edges still count below
    }
    out.tris.push_back(tri);
  }
  // Edge census: directed uses per undirected edge.
  std::vector<std::uint64_t> keys;  // (min << 33) | (max << 1) | (direction)
  keys.reserve(out.tris.size() * 3);
  for (const Tri& t : out.tris)
    for (int k = 0; k < 3; ++k) {
      const int u = t[std::size_t(k)], v = t[std::size_t((k + 1) % 3)];
      if (u == v) continue;
      const std::uint64_t lo = std::uint64_t(std::min(u, v)), hi = std::uint64_t(std::max(u, v));
      keys.push_back((lo << 33) | (hi << 1) | (u < v ? 0u : 1u));
    }
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    int forward = 0, backward = 0;
    while (j < keys.size() && (keys[j] >> 1) == (keys[i] >> 1)) {
      (keys[j] & 1u) ? ++backward : ++forward;
      ++j;
    }
    const int n = forward + backward;
    if (n == 1)
      ++r.boundary_edges;
    else if (n > 2)
      ++r.nonmanifold_edges;
    else if (forward != 1)
      ++r.inconsistent_edges;
    i = j;
  }
  // Global orientation: the signed volume is positive for an outward-oriented closed mesh.
  double vol = 0;
  for (const Tri& t : out.tris)
    vol +=
        Eigen::Vector3d(out.P.row(t[0])).dot(Eigen::Vector3d(out.P.row(t[1])).cross(Eigen::Vector3d(out.P.row(t[2]))));
  r.inward_oriented = vol < 0;
  return out;
}

// Signed crossings of every ray along axis `a` through the voxel centres of the slab
// (coordinate c == k), grouped by their b index. b = a+1, c = a+2 (cyclic), so that the 2D
// orientation in (b, c) is the a-component of the triangle normal.
class RayCaster {
 public:
  RayCaster(const Prepared& m, int axis, const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, double h)
      : m_(m), a_(axis), b_((axis + 1) % 3), c_((axis + 2) % 3), lo_(lo), hi_(hi), h_(h) {
    // Bucket triangles by the slabs (c index) their projection spans.
    const int nc = hi[c_] - lo[c_] + 1;
    std::vector<std::size_t> count(std::size_t(nc) + 1, 0);
    auto range = [&](const Tri& t, int axis_id, int& k0, int& k1) {
      double mn = m.P(t[0], axis_id), mx = mn;
      for (int q = 1; q < 3; ++q) {
        mn = std::min(mn, m.P(t[std::size_t(q)], axis_id));
        mx = std::max(mx, m.P(t[std::size_t(q)], axis_id));
      }
      k0 = std::max(int(std::ceil(mn / h)), lo[axis_id]);
      k1 = std::min(int(std::floor(mx / h)), hi[axis_id]);
    };
    for (const Tri& t : m.tris) {
      int k0, k1;
      range(t, c_, k0, k1);
      for (int k = k0; k <= k1; ++k) ++count[std::size_t(k - lo[c_]) + 1];
    }
    std::partial_sum(count.begin(), count.end(), count.begin());
    start_ = count;
    bucket_.resize(count.back());
    std::vector<std::size_t> fill(count.begin(), count.end() - 1);
    for (std::size_t t = 0; t < m.tris.size(); ++t) {
      int k0, k1;
      range(m.tris[t], c_, k0, k1);
      for (int k = k0; k <= k1; ++k) bucket_[fill[std::size_t(k - lo[c_])]++] = int(t);
    }
  }

  int slab_axis() const { return c_; }
  int row_axis() const { return b_; }

  /// rows[j - lo_b] = sorted crossings of the ray (b = j, c = k).
  void slab(int k, double orientation, std::vector<std::vector<Crossing>>& rows) const {
    rows.resize(std::size_t(hi_[b_] - lo_[b_] + 1));
    for (auto& r : rows) r.clear();
    const double pc = k * h_;
    const std::size_t s0 = start_[std::size_t(k - lo_[c_])], s1 = start_[std::size_t(k - lo_[c_]) + 1];
    for (std::size_t s = s0; s < s1; ++s) {
      const Tri& t = m_.tris[std::size_t(bucket_[s])];
      double mn = m_.P(t[0], b_), mx = mn;
      for (int q = 1; q < 3; ++q) {
        mn = std::min(mn, m_.P(t[std::size_t(q)], b_));
        mx = std::max(mx, m_.P(t[std::size_t(q)], b_));
      }
      const int j0 = std::max(int(std::ceil(mn / h_)), lo_[b_]), j1 = std::min(int(std::floor(mx / h_)), hi_[b_]);
      for (int j = j0; j <= j1; ++j) {
        const double pb = j * h_;
        double e0, e1, e2;
        const int s_ab = edge_sign(m_.P, t[0], t[1], b_, c_, pb, pc, e2);  // weight of vertex c
        const int s_bc = edge_sign(m_.P, t[1], t[2], b_, c_, pb, pc, e0);  // weight of vertex a
        const int s_ca = edge_sign(m_.P, t[2], t[0], b_, c_, pb, pc, e1);  // weight of vertex b
        if (s_ab == 0 || s_ab != s_bc || s_ab != s_ca) continue;
        const double sum = e0 + e1 + e2;
        double x;
        if (sum != 0)
          x = (e0 * m_.P(t[0], a_) + e1 * m_.P(t[1], a_) + e2 * m_.P(t[2], a_)) / sum;
        else
          x = (m_.P(t[0], a_) + m_.P(t[1], a_) + m_.P(t[2], a_)) / 3.0;  // unreachable for a real triangle
        rows[std::size_t(j - lo_[b_])].push_back({x, int(orientation) * s_ab});
      }
    }
    for (auto& r : rows) std::sort(r.begin(), r.end());
  }

 private:
  const Prepared& m_;
  int a_, b_, c_;
  Eigen::Vector3i lo_, hi_;
  double h_;
  std::vector<std::size_t> start_;
  std::vector<int> bucket_;
};

// ---- self-intersections: pairs of triangles without a common vertex that properly cross ----
inline double orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}

// Segment pq crosses the interior of triangle abc (strictly: touching is not counted).
bool segment_crosses(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                     const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double dp = orient3d(a, b, c, p), dq = orient3d(a, b, c, q);
  if (!((dp > 0 && dq < 0) || (dp < 0 && dq > 0))) return false;
  const double s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  return (s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0);
}

bool triangles_cross(const Prepared& m, const Tri& t, const Tri& u) {
  Eigen::Vector3d T[3], U[3];
  for (int k = 0; k < 3; ++k) {
    T[k] = m.P.row(t[std::size_t(k)]);
    U[k] = m.P.row(u[std::size_t(k)]);
  }
  for (int k = 0; k < 3; ++k) {
    if (segment_crosses(T[k], T[(k + 1) % 3], U[0], U[1], U[2])) return true;
    if (segment_crosses(U[k], U[(k + 1) % 3], T[0], T[1], T[2])) return true;
  }
  return false;
}

// Uniform grid of about one cell per triangle; each candidate pair is tested once, in the cell
// holding the lower corner of the intersection of the two bounding boxes.
std::int64_t count_self_intersections(const Prepared& m) {
  const std::size_t nt = m.tris.size();
  if (nt < 2) return 0;
  std::vector<Eigen::AlignedBox3d> box(nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) box[t].extend(Eigen::Vector3d(m.P.row(m.tris[t][std::size_t(k)])));
  const Eigen::Vector3d lo = m.P.colwise().minCoeff().transpose(), hi = m.P.colwise().maxCoeff().transpose();
  const int g = std::clamp(int(std::cbrt(double(nt))), 1, 200);
  const Eigen::Vector3d cell = ((hi - lo) / g).cwiseMax(1e-300);
  auto cell_of = [&](const Eigen::Vector3d& x) {
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int((x[a] - lo[a]) / cell[a]), 0, g - 1);
    return c;
  };
  auto cell_id = [&](const Eigen::Vector3i& c) {
    return (std::size_t(c.z()) * std::size_t(g) + std::size_t(c.y())) * std::size_t(g) + std::size_t(c.x());
  };
  const std::size_t ncells = std::size_t(g) * std::size_t(g) * std::size_t(g);
  std::vector<std::vector<int>> cells(ncells);
  for (std::size_t t = 0; t < nt; ++t) {
    const Eigen::Vector3i c0 = cell_of(box[t].min()), c1 = cell_of(box[t].max());
    for (int z = c0.z(); z <= c1.z(); ++z)
      for (int y = c0.y(); y <= c1.y(); ++y)
        for (int x = c0.x(); x <= c1.x(); ++x) cells[cell_id({x, y, z})].push_back(int(t));
  }
  std::vector<std::int64_t> per_cell(ncells, 0);
  tbb::parallel_for(std::size_t(0), ncells, [&](std::size_t id) {
    const auto& list = cells[id];
    std::int64_t n = 0;
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const Tri &t = m.tris[std::size_t(list[i])], &u = m.tris[std::size_t(list[j])];
        bool adjacent = false;
        for (int a : t)
          for (int b : u) adjacent |= a == b;
        if (adjacent) continue;
        const Eigen::AlignedBox3d both = box[std::size_t(list[i])].intersection(box[std::size_t(list[j])]);
        if (both.isEmpty() || cell_id(cell_of(both.min())) != id) continue;
        n += triangles_cross(m, t, u);
      }
    per_cell[id] = n;
  });
  return std::accumulate(per_cell.begin(), per_cell.end(), std::int64_t{0});
}

}  // namespace

std::vector<std::string> MeshVoxelizationReport::warnings() const {
  std::vector<std::string> w;
  if (boundary_edges || nonmanifold_edges) {
    std::ostringstream os;
    os << "mesh is not closed: " << boundary_edges << " boundary edges, " << nonmanifold_edges
       << " non-manifold edges; inside decided by a vote of the 6 axis rays (" << ambiguous_voxels
       << " voxels where the rays disagree)";
    w.push_back(os.str());
  } else if (ambiguous_voxels) {
    std::ostringstream os;
    os << "mesh has overlapping parts: " << ambiguous_voxels
       << " voxels have a winding number other than 0 or 1 (counted as inside when > 0)";
    w.push_back(os.str());
  }
  if (self_intersections) {
    std::ostringstream os;
    os << "mesh is self-intersecting: " << self_intersections << " pairs of triangles without a common vertex cross";
    w.push_back(os.str());
  }
  if (inconsistent_edges) {
    std::ostringstream os;
    os << "mesh orientation is inconsistent: " << inconsistent_edges
       << " edges are traversed in the same direction by both their triangles";
    w.push_back(os.str());
  }
  if (degenerate_triangles)
    w.push_back(std::to_string(degenerate_triangles) + " degenerate (zero-area) triangles ignored");
  if (inward_oriented) w.push_back("mesh is oriented inward (negative volume): orientation flipped");
  if (merged_vertices) w.push_back(std::to_string(merged_vertices) + " duplicate vertices (equal positions) merged");
  return w;
}

VoxelGrid voxelize_mesh(const PolygonMesh& mesh, const MeshVoxelizationParams& params, MeshVoxelizationReport* report) {
  MeshVoxelizationReport local;
  MeshVoxelizationReport& r = report ? *report : local;
  r = MeshVoxelizationReport{};
  const Prepared m = prepare(mesh, r);
  r.self_intersections = count_self_intersections(m);
  r.bbox_min = m.P.colwise().minCoeff();
  r.bbox_max = m.P.colwise().maxCoeff();
  const double side = (r.bbox_max - r.bbox_min).maxCoeff();
  double h = 0;
  if (params.resolution > 0) {
    if (params.resolution > 100000)
      throw InputError("mesh voxelization: resolution " + std::to_string(params.resolution) + " is absurd");
    if (!(side > 0)) throw InputError("mesh voxelization: the mesh bounding box is a single point");
    h = side / params.resolution;
  } else {
    h = params.h;
    if (!(h > 0) || !std::isfinite(h)) {
      std::ostringstream os;
      os << "mesh voxelization: give a resolution > 0 or a grid step h > 0 (got resolution " << params.resolution
         << ", h " << params.h << ")";
      throw InputError(os.str());
    }
  }
  r.h = h;
  // One empty voxel on every side: the extracted digital surface is closed.
  Eigen::Vector3i lo, hi;
  for (int c = 0; c < 3; ++c) {
    const double l = std::floor(r.bbox_min[c] / h) - 1, u = std::ceil(r.bbox_max[c] / h) + 1;
    if (!(std::abs(l) < 1e9 && std::abs(u) < 1e9))
      throw InputError("mesh voxelization: grid step too small for the mesh extent");
    lo[c] = int(l);
    hi[c] = int(u);
  }
  VoxelGrid grid(lo, hi, h);  // throws InputError for absurd sizes
  r.grid_size = grid.size();
  const double orientation = r.inward_oriented ? -1.0 : 1.0;

  if (r.closed()) {
    // Closed: rays along x; the winding number of a centre is the signed count of the crossings
    // beyond it. Slabs (z) are independent and write disjoint rows of the grid.
    RayCaster rc(m, 0, lo, hi, h);
    std::vector<std::int64_t> ambiguous(std::size_t(hi.z() - lo.z() + 1), 0);
    tbb::parallel_for(lo.z(), hi.z() + 1, [&](int z) {
      std::vector<std::vector<Crossing>> rows;
      rc.slab(z, orientation, rows);
      for (int y = lo.y(); y <= hi.y(); ++y) {
        const auto& cr = rows[std::size_t(y - lo.y())];
        if (cr.empty()) continue;
        int w = 0;
        for (const Crossing& c : cr) w += c.sign;  // total: 0 for a closed mesh
        std::size_t next = 0;
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const double px = x * h;
          while (next < cr.size() && cr[next].x <= px) w -= cr[next++].sign;
          if (w > 0) grid.set(x, y, z, true);
          if (w != 0 && w != 1) ++ambiguous[std::size_t(z - lo.z())];
        }
      }
    });
    r.ambiguous_voxels = std::accumulate(ambiguous.begin(), ambiguous.end(), std::int64_t{0});
  } else {
    // Open: the winding number depends on the ray; each of the 6 axis rays (+/- x, y, z) votes.
    const Eigen::Vector3i n = grid.size();
    const double vote_bytes = double(n.x()) * n.y() * n.z();
    if (vote_bytes > 4294967296.0) {
      std::ostringstream os;
      os << "mesh voxelization: the mesh is not closed (" << r.boundary_edges << " boundary edges, "
         << r.nonmanifold_edges << " non-manifold edges) and the ray vote at this resolution would need "
         << vote_bytes / 1073741824.0 << " GiB; close the mesh or use a coarser resolution";
      throw InputError(os.str());
    }
    std::vector<std::uint8_t> votes(std::size_t(vote_bytes), 0);
    auto index = [&](const Eigen::Vector3i& p) {
      return (std::size_t(p.z() - lo.z()) * std::size_t(n.y()) + std::size_t(p.y() - lo.y())) * std::size_t(n.x()) +
             std::size_t(p.x() - lo.x());
    };
    for (int a = 0; a < 3; ++a) {
      RayCaster rc(m, a, lo, hi, h);
      const int b = rc.row_axis(), c = rc.slab_axis();
      // Each task owns the voxels with coordinate c == k: writes are disjoint.
      tbb::parallel_for(lo[c], hi[c] + 1, [&](int k) {
        std::vector<std::vector<Crossing>> rows;
        rc.slab(k, orientation, rows);
        for (int j = lo[b]; j <= hi[b]; ++j) {
          const auto& cr = rows[std::size_t(j - lo[b])];
          if (cr.empty()) continue;
          int total = 0;
          for (const Crossing& q : cr) total += q.sign;
          // The centre is perturbed by +delta along a too (as in the closed case, where a crossing
          // exactly at the centre is not "beyond" it): a crossing at the centre counts as below,
          // so both rays agree with the half-open rule used on the other axes.
          int before = 0;  // sum of signs of crossings at or below the centre
          std::size_t next = 0;
          Eigen::Vector3i p;
          p[b] = j;
          p[c] = k;
          for (int i = lo[a]; i <= hi[a]; ++i) {
            const double px = i * h;
            while (next < cr.size() && cr[next].x <= px) before += cr[next++].sign;
            p[a] = i;
            const int w_plus = total - before;  // ray towards +a: crossings beyond the centre
            const int w_minus = -before;        // ray towards -a: crossings below it
            votes[index(p)] += std::uint8_t((w_plus > 0) + (w_minus > 0));
          }
        }
      });
    }
    std::int64_t ambiguous = 0;
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const std::uint8_t v = votes[index(Eigen::Vector3i(x, y, z))];
          if (v >= 4) grid.set(x, y, z, true);
          if (v != 0 && v != 6) ++ambiguous;
        }
    r.ambiguous_voxels = ambiguous;
  }
  r.inside_voxels = grid.count();
  if (r.inside_voxels == 0) {
    std::ostringstream os;
    os << "mesh voxelization: no voxel centre lies inside the mesh at h = " << h
       << " (resolution too coarse, or the mesh encloses no volume)";
    throw InputError(os.str());
  }
  return grid;
}

}  // namespace corrlap
