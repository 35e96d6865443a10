#include "loop_subdivision.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <numbers>
#include <string>
#include <vector>

namespace corrlap {

namespace {

struct EdgeSide {
  int lo, hi;    // vertex ids, lo < hi
  int opposite;  // the third vertex of the triangle
  int triangle;  // which triangle, and which of its edges (0: v0v1, 1: v1v2, 2: v2v0)
  int local;
};

}  // namespace

TriangleMesh loop_subdivide(const TriangleMesh& mesh) {
  const Eigen::MatrixX3d& V = mesh.positions;
  const TriangleIndices& T = mesh.triangles;
  const Eigen::Index nv = V.rows(), nt = T.rows();
  // Edges by sorting the triangle sides: each undirected edge appears once or twice.
  std::vector<EdgeSide> sides;
  sides.reserve(std::size_t(3 * nt));
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = T(t, k), b = T(t, (k + 1) % 3), c = T(t, (k + 2) % 3);
      if (a < 0 || b < 0 || c < 0 || a >= nv || b >= nv || c >= nv)
        throw InputError("loop subdivision: triangle " + std::to_string(t) + " refers to a missing vertex");
      if (a == b || b == c || a == c)
        throw InputError("loop subdivision: triangle " + std::to_string(t) + " repeats a vertex");
      sides.push_back({std::min(a, b), std::max(a, b), c, int(t), k});
    }
  std::sort(sides.begin(), sides.end(),
            [](const EdgeSide& x, const EdgeSide& y) { return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi; });

  // Edge points, and the id of the edge point of every triangle side.
  std::vector<Eigen::Vector3d> edge_points;
  edge_points.reserve(sides.size() / 2 + 16);
  std::vector<int> side_point(std::size_t(3 * nt));
  std::vector<char> on_boundary(std::size_t(nv), 0);
  std::vector<Eigen::Vector3d> boundary_sum(std::size_t(nv), Eigen::Vector3d::Zero());
  std::vector<int> boundary_count(std::size_t(nv), 0);
  std::vector<Eigen::Vector3d> neighbour_sum(std::size_t(nv), Eigen::Vector3d::Zero());
  std::vector<int> valence(std::size_t(nv), 0);
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
    const int a = sides[i].lo, b = sides[i].hi;
    if (j - i > 2)
      throw InputError("loop subdivision: edge (" + std::to_string(a) + ", " + std::to_string(b) + ") has " +
                       std::to_string(j - i) + " triangles; the mesh must be a manifold (at most two per edge)");
    const Eigen::Vector3d pa = V.row(a), pb = V.row(b);
    if (j - i == 2) {
      edge_points.push_back(0.375 * (pa + pb) +
                            0.125 * (V.row(sides[i].opposite) + V.row(sides[i + 1].opposite)).transpose());
    } else {
      edge_points.push_back(0.5 * (pa + pb));
      on_boundary[std::size_t(a)] = on_boundary[std::size_t(b)] = 1;
      boundary_sum[std::size_t(a)] += pb;
      boundary_sum[std::size_t(b)] += pa;
      ++boundary_count[std::size_t(a)];
      ++boundary_count[std::size_t(b)];
    }
    neighbour_sum[std::size_t(a)] += pb;
    neighbour_sum[std::size_t(b)] += pa;
    ++valence[std::size_t(a)];
    ++valence[std::size_t(b)];
    const int id = int(nv) + int(edge_points.size()) - 1;
    for (std::size_t s = i; s < j; ++s) side_point[std::size_t(3 * sides[s].triangle + sides[s].local)] = id;
    i = j;
  }

  TriangleMesh out;
  out.positions.resize(nv + Eigen::Index(edge_points.size()), 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    const std::size_t i = std::size_t(v);
    const Eigen::Vector3d p = V.row(v);
    Eigen::Vector3d q = p;
    if (on_boundary[i]) {
      // A vertex where the boundary is not a simple curve (more than two boundary edges) stays put.
      if (boundary_count[i] == 2) q = 0.75 * p + 0.125 * boundary_sum[i];
    } else if (valence[i] > 0) {
      const double n = valence[i];
      const double c = 0.375 + 0.25 * std::cos(2.0 * std::numbers::pi / n);
      const double beta = (0.625 - c * c) / n;
      q = (1.0 - n * beta) * p + beta * neighbour_sum[i];
    }
    out.positions.row(v) = q;
  }
  for (std::size_t e = 0; e < edge_points.size(); ++e) out.positions.row(nv + Eigen::Index(e)) = edge_points[e];

  out.triangles.resize(4 * nt, 3);
  for (Eigen::Index t = 0; t < nt; ++t) {
    const int m01 = side_point[std::size_t(3 * t)], m12 = side_point[std::size_t(3 * t + 1)],
              m20 = side_point[std::size_t(3 * t + 2)];
    out.triangles.row(4 * t) << T(t, 0), m01, m20;
    out.triangles.row(4 * t + 1) << m01, T(t, 1), m12;
    out.triangles.row(4 * t + 2) << m20, m12, T(t, 2);
    out.triangles.row(4 * t + 3) << m01, m12, m20;
  }
  return out;
}

int loop_refine(TriangleMesh& mesh, long long min_vertices) {
  int steps = 0;
  // Each step multiplies the vertex count by about 4: 8 steps are a factor 65 000.
  while (mesh.positions.rows() < min_vertices) {
    if (steps == 8)
      throw InputError("loop subdivision: " + std::to_string(min_vertices) +
                       " vertices would need more than 8 subdivision steps from " +
                       std::to_string(mesh.positions.rows()) + " vertices");
    mesh = loop_subdivide(mesh);
    ++steps;
  }
  return steps;
}

}  // namespace corrlap
