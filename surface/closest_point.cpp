#include "closest_point.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <limits>
#include <string>

namespace corrlap {

ClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  ClosestPoint best;
  best.distance = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Eigen::Vector3d& w) {
    const Eigen::Vector3d q = w[0] * a + w[1] * b + w[2] * c;
    const double d = (p - q).norm();
    if (d < best.distance) {
      best.distance = d;
      best.barycentric = w;
      best.point = q;
    }
  };
  // The foot of the perpendicular on the plane, when it falls inside the triangle: barycentric
  // coordinates from the 2 x 2 normal equations of p - a = beta (b - a) + gamma (c - a).
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = d.dot(e0), d21 = d.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  if (det > 1e-14 * d00 * d11) {
    const double beta = (d11 * d20 - d01 * d21) / det, gamma = (d00 * d21 - d01 * d20) / det;
    if (beta >= 0 && gamma >= 0 && beta + gamma <= 1) {
      consider(Eigen::Vector3d(1 - beta - gamma, beta, gamma));
      return best;
    }
  }
  // Otherwise the nearest point is on the boundary: the nearest of the three edges' nearest points.
  const auto edge = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v, int iu, int iv) {
    const Eigen::Vector3d uv = v - u;
    const double len2 = uv.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - u).dot(uv) / len2, 0.0, 1.0) : 0.0;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    w[iu] = 1 - t;
    w[iv] = t;
    consider(w);
  };
  edge(a, b, 0, 1);
  edge(b, c, 1, 2);
  edge(c, a, 2, 0);
  return best;
}

TriangleLocator::TriangleLocator(const Eigen::MatrixX3d& V, const TriangleIndices& T) : V_(V), T_(T) {
  if (V.rows() == 0 || T.rows() == 0) throw InputError("closest points: the mesh is empty");
  if (!V.allFinite()) throw InputError("closest points: a vertex position is not finite");
  if (T.minCoeff() < 0 || T.maxCoeff() >= V.rows())
    throw InputError("closest points: a triangle refers to a missing vertex");
  const Eigen::Vector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  double edges = 0;
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    for (int k = 0; k < 3; ++k) edges += (V.row(T(t, k)) - V.row(T(t, (k + 1) % 3))).norm();
  // Cells of about two mean edge lengths hold a handful of triangles each; the extent / 1024 floor
  // and the cap on the cell count keep a mesh with a few huge triangles from a huge grid.
  const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
  cell_ = std::max(2.0 * edges / double(3 * T.rows()), extent / 1024.0);
  while (true) {
    for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, int(std::ceil((hi[a] - lo[a]) / cell_)) + 1);
    if (double(dims_[0]) * dims_[1] * dims_[2] <= 8.0 * double(T.rows()) + 64) break;
    cell_ *= 1.5;
  }
  origin_ = lo;
  const auto cell_of = [&](const Eigen::Vector3d& x) {
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((x[a] - origin_[a]) / cell_)), 0, dims_[a] - 1);
    return c;
  };
  const auto index = [&](int x, int y, int z) { return (std::size_t(z) * dims_[1] + std::size_t(y)) * dims_[0] + x; };
  const std::size_t cells = std::size_t(dims_[0]) * dims_[1] * dims_[2];
  std::vector<int> count(cells + 1, 0);
  const auto for_cells = [&](Eigen::Index t, auto&& f) {
    Eigen::Vector3d tlo = V.row(T(t, 0)), thi = tlo;
    for (int k = 1; k < 3; ++k) {
      tlo = tlo.cwiseMin(V.row(T(t, k)).transpose());
      thi = thi.cwiseMax(V.row(T(t, k)).transpose());
    }
    const Eigen::Vector3i c0 = cell_of(tlo), c1 = cell_of(thi);
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x) f(index(x, y, z));
  };
  for (Eigen::Index t = 0; t < T.rows(); ++t) for_cells(t, [&](std::size_t i) { ++count[i + 1]; });
  for (std::size_t i = 0; i < cells; ++i) count[i + 1] += count[i];
  cell_start_ = count;
  cell_triangles_.resize(std::size_t(count[cells]));
  for (Eigen::Index t = 0; t < T.rows(); ++t)
    for_cells(t, [&](std::size_t i) { cell_triangles_[std::size_t(count[i]++)] = int(t); });
}

ClosestPoint TriangleLocator::closest(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) throw InputError("closest points: a query point is not finite");
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) c[a] = std::clamp(int(std::floor((p[a] - origin_[a]) / cell_)), 0, dims_[a] - 1);
  ClosestPoint best;
  best.distance = std::numeric_limits<double>::infinity();
  const int max_ring = dims_.maxCoeff();
  for (int r = 0; r <= max_ring; ++r) {
    // The shell of cells at Chebyshev distance r from the query cell.
    for (int dz = -r; dz <= r; ++dz) {
      const int z = c[2] + dz;
      if (z < 0 || z >= dims_[2]) continue;
      for (int dy = -r; dy <= r; ++dy) {
        const int y = c[1] + dy;
        if (y < 0 || y >= dims_[1]) continue;
        const bool face = std::abs(dz) == r || std::abs(dy) == r;
        for (int dx = -r; dx <= r; dx += face ? 1 : 2 * std::max(r, 1)) {
          const int x = c[0] + dx;
          if (x < 0 || x >= dims_[0]) continue;
          const std::size_t i = (std::size_t(z) * dims_[1] + std::size_t(y)) * dims_[0] + x;
          for (int k = cell_start_[i]; k < cell_start_[i + 1]; ++k) {
            const int t = cell_triangles_[std::size_t(k)];
            const ClosestPoint q = closest_point_on_triangle(p, V_.row(T_(t, 0)), V_.row(T_(t, 1)), V_.row(T_(t, 2)));
            if (q.distance < best.distance) {
              best = q;
              best.triangle = t;
            }
          }
        }
      }
    }
    // Every cell of ring r + 1 is at least r cell widths away from p (p lies in, or beyond the
    // grid behind, its clamped cell).
    if (best.distance <= double(r) * cell_) break;
  }
  return best;
}

std::vector<ClosestPoint> closest_points(const TriangleLocator& locator, const Eigen::MatrixX3d& P) {
  std::vector<ClosestPoint> out(std::size_t(P.rows()));
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, P.rows(), 1024),
                    [&](const tbb::blocked_range<Eigen::Index>& r) {
                      for (Eigen::Index i = r.begin(); i != r.end(); ++i)
                        out[std::size_t(i)] = locator.closest(P.row(i).transpose());
                    });
  return out;
}

}  // namespace corrlap
