#pragma once
// Vertex-row gather for vertex-based 4x4 face matrices (spec §0 assembly A[v_i,v_j] += A_f[i,j]):
// every matrix entry is written once, by the task that owns its column, summing the incident
// faces in ascending order, so the result is deterministic and bitwise identical for any thread
// count. No sorting of contributions and no per-face heap allocation: this is the fast path used
// by the quad discretizations (the generic AssemblyPlan sorts every contribution). Internal header.
#include <Eigen/Sparse>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <vector>

#include <corrlap/core/surfel_mesh.hpp>

namespace corrlap::detail {

/// Face corners (4 f + i) incident to each vertex, ascending.
struct VertexCorners {
  std::vector<int> start;   // #V + 1
  std::vector<int> corner;  // 4 #F
  int max_degree = 0;
};

inline VertexCorners vertex_corners(const SurfelMesh& mesh) {
  VertexCorners vc;
  const int V = mesh.num_vertices(), C = 4 * mesh.num_faces();
  const int* ids = mesh.faces.data();
  vc.start.assign(std::size_t(V) + 1, 0);
  for (int c = 0; c < C; ++c) ++vc.start[std::size_t(ids[c]) + 1];
  for (int v = 0; v < V; ++v) {
    vc.max_degree = std::max(vc.max_degree, vc.start[std::size_t(v) + 1]);
    vc.start[std::size_t(v) + 1] += vc.start[std::size_t(v)];
  }
  vc.corner.resize(std::size_t(C));
  std::vector<int> fill(vc.start.begin(), vc.start.end() - 1);
  for (int c = 0; c < C; ++c) vc.corner[std::size_t(fill[std::size_t(ids[c])]++)] = c;
  return vc;
}

/// Sorted distinct ids of the corners of the faces incident to v, into buf; returns the count.
inline int vertex_neighbours(const int* faces, const VertexCorners& vc, int v, int* buf) {
  int n = 0;
  for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
    const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
    for (int j = 0; j < 4; ++j) {
      const int w = f[j];
      int p = n;
      while (p > 0 && buf[p - 1] > w) --p;
      if (p > 0 && buf[p - 1] == w) continue;
      for (int q = n; q > p; --q) buf[q] = buf[q - 1];
      buf[p] = w;
      ++n;
    }
  }
  return n;
}

inline int find_sorted(const int* buf, int n, int w) { return int(std::lower_bound(buf, buf + n, w) - buf); }

/// Assembles Count symmetric matrices. kernel(f, i, rows) writes row i of the local matrix m of
/// face f into rows[4 m .. 4 m + 3]. Local matrices must be symmetric (column v is row v).
template <int Count, class RowKernel>
void gather_quad_rows(const SurfelMesh& mesh, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out) {
  const int V = mesh.num_vertices();
  const int* faces = mesh.faces.data();
  const std::size_t cap = std::size_t(4 * vc.max_degree + 1);
  std::vector<int> outer(std::size_t(V) + 1, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 8192), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> buf(cap);
    for (int v = r.begin(); v != r.end(); ++v) outer[std::size_t(v) + 1] = vertex_neighbours(faces, vc, v, buf.data());
  });
  for (int v = 0; v < V; ++v) outer[std::size_t(v) + 1] += outer[std::size_t(v)];
  const Eigen::Index nnz = outer[std::size_t(V)];
  for (auto* A : out) {
    A->resize(V, V);
    A->resizeNonZeros(nnz);
    std::copy(outer.begin(), outer.end(), A->outerIndexPtr());
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    std::vector<int> buf(cap);
    std::array<int*, Count> inner;
    std::array<double*, Count> val;
    for (int m = 0; m < Count; ++m) {
      inner[std::size_t(m)] = out[std::size_t(m)]->innerIndexPtr();
      val[std::size_t(m)] = out[std::size_t(m)]->valuePtr();
    }
    double rows[4 * Count];
    for (int v = r.begin(); v != r.end(); ++v) {
      const int n = vertex_neighbours(faces, vc, v, buf.data());
      const std::size_t o = std::size_t(outer[std::size_t(v)]);
      for (int m = 0; m < Count; ++m) {
        std::copy_n(buf.data(), n, inner[std::size_t(m)] + o);
        std::fill_n(val[std::size_t(m)] + o, n, 0.0);
      }
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int c = vc.corner[std::size_t(a)];
        const int f = c >> 2, i = c & 3;
        kernel(f, i, rows);
        for (int j = 0; j < 4; ++j) {
          const std::size_t k = o + std::size_t(find_sorted(buf.data(), n, faces[4 * f + j]));
          for (int m = 0; m < Count; ++m) val[std::size_t(m)][k] += rows[4 * m + j];
        }
      }
    }
  });
}

/// Diagonal matrix with entry v = sum over the corners (f, i) at v, ascending f, of value(f, i).
template <class CornerValue>
Eigen::SparseMatrix<double> gather_corner_diagonal(const SurfelMesh& mesh, const VertexCorners& vc, CornerValue&& value) {
  const int V = mesh.num_vertices();
  Eigen::SparseMatrix<double> D(V, V);
  D.resizeNonZeros(V);
  int* outer = D.outerIndexPtr();
  int* inner = D.innerIndexPtr();
  double* val = D.valuePtr();
  outer[V] = V;
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 8192), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v != r.end(); ++v) {
      double s = 0.0;
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int c = vc.corner[std::size_t(a)];
        s += value(c >> 2, c & 3);
      }
      outer[v] = v;
      inner[v] = v;
      val[v] = s;
    }
  });
  return D;
}

}  // namespace corrlap::detail
