#pragma once
// Vertex-row gather for vertex-based 4x4 face matrices (spec §0 assembly A[v_i,v_j] += A_f[i,j]):
// every matrix entry is written once, by the task that owns its column, summing the incident
// faces in ascending order, so the result is deterministic and bitwise identical for any thread
// count. No sorting of contributions and no per-face heap allocation: this is the fast path used
// by the quad discretizations (the generic AssemblyPlan sorts every contribution). Internal header.
#include <Eigen/Sparse>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
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

/// Per-thread scratch for column assembly: stamp[w] marks vertex w as seen for the current
/// column (stamps differ per column and per pass, so nothing is ever reset) and pos[w] is its
/// position in the column. One allocation per thread, none per face or per vertex.
struct ColumnScratch {
  std::vector<int> stamp, pos, list;
  ColumnScratch(int num_vertices, std::size_t list_capacity)
      : stamp(std::size_t(num_vertices), -1), pos(std::size_t(num_vertices), 0), list(list_capacity) {}
};

/// Assembles Count symmetric matrices. kernel(f, i, rows) writes row i of the local matrix m of
/// face f into rows[4 m .. 4 m + 3]. Local matrices must be symmetric (column v is row v).
template <int Count, class RowKernel>
void gather_quad_rows(const SurfelMesh& mesh, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out) {
  const int V = mesh.num_vertices();
  const int* faces = mesh.faces.data();
  const std::size_t cap = std::size_t(4 * vc.max_degree + 1);
  tbb::enumerable_thread_specific<ColumnScratch> scratch([&] { return ColumnScratch(V, cap); });
  std::vector<int> outer(std::size_t(V) + 1, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    int* stamp = scratch.local().stamp.data();
    for (int v = r.begin(); v != r.end(); ++v) {
      int n = 0;
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j)
          if (stamp[f[j]] != v) stamp[f[j]] = v, ++n;
      }
      outer[std::size_t(v) + 1] = n;
    }
  });
  for (int v = 0; v < V; ++v) outer[std::size_t(v) + 1] += outer[std::size_t(v)];
  const Eigen::Index nnz = outer[std::size_t(V)];
  for (auto* A : out) {
    A->resize(V, V);
    A->resizeNonZeros(nnz);
    std::copy(outer.begin(), outer.end(), A->outerIndexPtr());
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    ColumnScratch& sc = scratch.local();
    int* stamp = sc.stamp.data();
    int* pos = sc.pos.data();
    int* list = sc.list.data();
    std::array<int*, Count> inner;
    std::array<double*, Count> val;
    for (int m = 0; m < Count; ++m) {
      inner[std::size_t(m)] = out[std::size_t(m)]->innerIndexPtr();
      val[std::size_t(m)] = out[std::size_t(m)]->valuePtr();
    }
    double rows[4 * Count];
    for (int v = r.begin(); v != r.end(); ++v) {
      const int mark = V + v;  // distinct from the first pass's stamps
      int n = 0;
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j)
          if (stamp[f[j]] != mark) stamp[f[j]] = mark, list[n++] = f[j];
      }
      std::sort(list, list + n);
      const std::size_t o = std::size_t(outer[std::size_t(v)]);
      for (int t = 0; t < n; ++t) pos[list[t]] = t;
      for (int m = 0; m < Count; ++m) {
        std::copy_n(list, n, inner[std::size_t(m)] + o);
        std::fill_n(val[std::size_t(m)] + o, n, 0.0);
      }
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int c = vc.corner[std::size_t(a)];
        const int f = c >> 2, i = c & 3;
        kernel(f, i, rows);
        for (int j = 0; j < 4; ++j) {
          const std::size_t k = o + std::size_t(pos[faces[4 * f + j]]);
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
