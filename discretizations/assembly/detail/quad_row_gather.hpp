#pragma once
// Vertex-row gather for vertex-based 4x4 face matrices (docs/math.md §0 assembly A[v_i,v_j] += A_f[i,j]):
// every matrix entry is written once, by the task that owns its column, summing the incident
// faces in ascending order, so the result is deterministic and bitwise identical for any thread
// count. No sorting of contributions and no per-face heap allocation: this is the fast path used
// by the quad discretizations (the generic AssemblyPlan sorts every contribution). Internal header.
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <corrlap/core/surfel_mesh.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <cstdint>
#include <memory>
#include <vector>

#include "huge_pages.hpp"
#include "storage.hpp"

namespace corrlap::detail {

/// Two doubles in one SSE2 / NEON register (GCC and Clang vector extension): the stiffness and mass
/// sums of one column entry (gather_quad_row_pairs).
typedef double PairLanes __attribute__((vector_size(16)));

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
  assign_on_huge_pages(vc.start, std::size_t(V) + 1);
  for (int c = 0; c < C; ++c) ++vc.start[std::size_t(ids[c]) + 1];
  for (int v = 0; v < V; ++v) {
    vc.max_degree = std::max(vc.max_degree, vc.start[std::size_t(v) + 1]);
    vc.start[std::size_t(v) + 1] += vc.start[std::size_t(v)];
  }
  assign_on_huge_pages(vc.corner, std::size_t(C));
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

/// Column pattern pass 1: outer[v + 1] = number of distinct rows of column v (the vertices of the
/// faces around v), then the prefix sum, so outer is the CSC outer index array (V + 1 entries).
/// Uses stamp marks v; column_rows uses V + v, so the two passes never reset the stamps.
inline void count_column_rows(const int* faces, const VertexCorners& vc, int V,
                              tbb::enumerable_thread_specific<ColumnScratch>& scratch, int* outer) {
  outer[0] = 0;
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    int* stamp = scratch.local().stamp.data();
    for (int v = r.begin(); v != r.end(); ++v) {
      int n = 0;
      for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
        const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
        for (int j = 0; j < 4; ++j)
          if (stamp[f[j]] != v) stamp[f[j]] = v, ++n;
      }
      outer[v + 1] = n;
    }
  });
  for (int v = 0; v < V; ++v) outer[v + 1] += outer[v];
}

/// Column pattern pass 2: the sorted distinct rows of column v written to `list`; returns their
/// number and sets pos[row] to each row's position in the column.
inline int column_rows(const int* faces, const VertexCorners& vc, int V, int v, ColumnScratch& sc) {
  const int mark = V + v;  // distinct from count_column_rows' stamps
  int* stamp = sc.stamp.data();
  int* list = sc.list.data();
  int n = 0;
  for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
    const int* f = faces + (vc.corner[std::size_t(a)] & ~3);
    for (int j = 0; j < 4; ++j)
      if (stamp[f[j]] != mark) stamp[f[j]] = mark, list[n++] = f[j];
  }
  std::sort(list, list + n);
  for (int t = 0; t < n; ++t) sc.pos[std::size_t(list[t])] = t;
  return n;
}

/// No-op column finisher (see the overloads taking `finish`).
struct NoColumnFinish {
  template <std::size_t N>
  void operator()(int, const std::array<double*, N>&, int) const {}
};

/// Assembles Count matrices. kernel(f, i, rows) writes column i of the local matrix m of face f
/// into rows[4 m .. 4 m + 3] (rows[4 m + j] = A_f[j, i], added at row v_j of column v_i); for the
/// usual symmetric local matrices that is row i. Then finish(v, column_values, n) once per column
/// v after its sums are complete, where column_values[m] points at the n values of column v in
/// matrix m (e.g. to negate a column while it is in cache: the same bits as scaling the finished
/// matrix afterwards).
template <int Count, class RowKernel, class ColumnFinish>
void gather_quad_rows(const SurfelMesh& mesh, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out, ColumnFinish&& finish) {
  const int V = mesh.num_vertices();
  const int* faces = mesh.faces.data();
  const std::size_t cap = std::size_t(4 * vc.max_degree + 1);
  tbb::enumerable_thread_specific<ColumnScratch> scratch([&] { return ColumnScratch(V, cap); });
  std::vector<int> outer(std::size_t(V) + 1, 0);
  count_column_rows(faces, vc, V, scratch, outer.data());
  const Eigen::Index nnz = outer[std::size_t(V)];
  for (auto* A : out) {
    size_for_fill(*A, V, nnz);
    std::copy(outer.begin(), outer.end(), A->outerIndexPtr());
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 4096), [&](const tbb::blocked_range<int>& r) {
    ColumnScratch& sc = scratch.local();
    const int* pos = sc.pos.data();
    const int* list = sc.list.data();
    std::array<int*, Count> inner;
    std::array<double*, Count> val;
    for (int m = 0; m < Count; ++m) {
      inner[std::size_t(m)] = out[std::size_t(m)]->innerIndexPtr();
      val[std::size_t(m)] = out[std::size_t(m)]->valuePtr();
    }
    double rows[4 * Count];
    for (int v = r.begin(); v != r.end(); ++v) {
      const int n = column_rows(faces, vc, V, v, sc);
      const std::size_t o = std::size_t(outer[std::size_t(v)]);
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
      std::array<double*, Count> col;
      for (int m = 0; m < Count; ++m) col[std::size_t(m)] = val[std::size_t(m)] + o;
      finish(v, col, n);
    }
  });
}

template <int Count, class RowKernel>
void gather_quad_rows(const SurfelMesh& mesh, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out) {
  gather_quad_rows<Count>(mesh, vc, kernel, out, NoColumnFinish{});
}

/// Vertex pattern of a quad mesh (held by QuadPattern, quad_pattern.hpp): incidence (vertex ->
/// corners, ascending), the CSC column structure (sorted distinct rows of each column) and, for
/// every incidence a (in vc order), the positions slot[4a + j] of corner j of its face inside the
/// column. Assembling through it only writes values, each entry once. Column sizes are bounded by
/// 65535 (uint16 slots): beyond that has_slots is false and only vc is set (direct gather).
struct QuadVertexPattern {
  int num_vertices = 0;
  bool has_slots = false;
  VertexCorners vc;
  std::vector<int> outer;           // #V + 1
  std::vector<int> inner;           // nnz, sorted within each column
  std::vector<std::uint16_t> slot;  // 4 per incidence
};

/// Columns of at most this many entries are summed on the stack by gather_quad_row_pairs.
inline constexpr int kPairColumnMax = 64;

/// gather_quad_rows through the pattern for two matrices and no column finisher, when every
/// column has at most kPairColumnMax entries (surfel meshes have at most 25). Entry k of both
/// columns is summed in one 2-lane vector, so a corner's contribution is one vector add instead of
/// two scalar read-modify-writes; lane m adds exactly what the scalar sum of matrix m adds, in the
/// same order, so the bits are the same. Timings: bench/RESULTS.md, "Assembly: record of
/// experiments" (fem after the paired gather).
template <class RowKernel>
void gather_quad_row_pairs(const QuadVertexPattern& p, RowKernel&& kernel, Eigen::SparseMatrix<double>& A0,
                           Eigen::SparseMatrix<double>& A1) {
  const int V = p.num_vertices;
  const Eigen::Index nnz = p.outer[std::size_t(V)];
  // Sized in two tasks, so that the second matrix's arrays (the outer index that Eigen's resize
  // zeroes, among others) come from a TBB worker's glibc arena, which keeps and reuses freed pages:
  // far fewer page faults on fresh output (bench/RESULTS.md, "Assembly: record of experiments",
  // "L and M sized in two tasks"). On one thread both run inline. Same bits either way.
  tbb::parallel_invoke([&] { size_for_fill(A0, V, nnz); }, [&] { size_for_fill(A1, V, nnz); });
  int* const inner0 = A0.innerIndexPtr();
  int* const inner1 = A1.innerIndexPtr();
  double* const val0 = A0.valuePtr();
  double* const val1 = A1.valuePtr();
  int* const outer0 = A0.outerIndexPtr();
  int* const outer1 = A1.outerIndexPtr();
  const int* const vstart = p.vc.start.data();
  const int* const vcorner = p.vc.corner.data();
  const std::uint16_t* const slot = p.slot.data();
  const int* const outer = p.outer.data();
  const int* const pin = p.inner.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 2048), [&](const tbb::blocked_range<int>& r) {
    double rows[8];
    PairLanes sum[kPairColumnMax];
    const std::size_t b = std::size_t(outer[r.begin()]), e = std::size_t(outer[r.end()]);
    std::copy(pin + b, pin + e, inner0 + b);
    std::copy(pin + b, pin + e, inner1 + b);
    std::copy(outer + r.begin(), outer + r.end(), outer0 + r.begin());
    std::copy(outer + r.begin(), outer + r.end(), outer1 + r.begin());
    for (int v = r.begin(); v != r.end(); ++v) {
      const std::size_t o = std::size_t(outer[v]);
      const int n = outer[v + 1] - outer[v];
      for (int k = 0; k < n; ++k) sum[k] = PairLanes{0.0, 0.0};
      for (int a = vstart[v]; a < vstart[v + 1]; ++a) {
        const int c = vcorner[a];
        kernel(c >> 2, c & 3, rows);
        const std::uint16_t* s = slot + 4 * std::size_t(a);
        for (int j = 0; j < 4; ++j) sum[s[j]] += PairLanes{rows[j], rows[4 + j]};
      }
      double* const c0 = val0 + o;
      double* const c1 = val1 + o;
      for (int k = 0; k < n; ++k) c0[k] = sum[k][0], c1[k] = sum[k][1];
    }
  });
  outer0[V] = int(nnz);
  outer1[V] = int(nnz);
}

/// Same result, bit for bit, as gather_quad_rows(mesh, vc, ...) (same entries, same summation
/// order: incident faces ascending), but with the pattern precomputed: per column it copies the
/// row indices and accumulates the rows at their cached slots.
template <int Count, class RowKernel, class ColumnFinish>
void gather_quad_rows(const QuadVertexPattern& p, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out, ColumnFinish&& finish) {
  const int V = p.num_vertices;
  const Eigen::Index nnz = p.outer[std::size_t(V)];
  for (auto* A : out) size_for_fill(*A, V, nnz);
  std::array<int*, Count> inner;
  std::array<double*, Count> val;
  std::array<int*, Count> outer_out;
  for (int m = 0; m < Count; ++m) {
    inner[std::size_t(m)] = out[std::size_t(m)]->innerIndexPtr();
    val[std::size_t(m)] = out[std::size_t(m)]->valuePtr();
    outer_out[std::size_t(m)] = out[std::size_t(m)]->outerIndexPtr();
  }
  const int* vstart = p.vc.start.data();
  const int* vcorner = p.vc.corner.data();
  const std::uint16_t* slot = p.slot.data();
  const int* outer = p.outer.data();
  const int* pin = p.inner.data();
  // Columns of up to kStack entries (all of them on surfel meshes, at most 25) are summed in a
  // stack buffer and then stored once: the outputs are fresh memory, each value is written once
  // instead of zeroed and then updated 4 times in place (the summation order, hence every bit,
  // is the in-place one). Longer columns sum in place. Plain stores: streaming (non-temporal) ones
  // are slower on the VMs measured (bench/RESULTS.md, "Assembly: record of experiments").
  constexpr int kStack = 64;
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 2048), [&](const tbb::blocked_range<int>& r) {
    double rows[4 * Count];
    double acc[Count][kStack];
    const std::size_t b = std::size_t(outer[r.begin()]), e = std::size_t(outer[r.end()]);
    for (int m = 0; m < Count; ++m) {
      std::copy(pin + b, pin + e, inner[std::size_t(m)] + b);
      std::copy(outer + r.begin(), outer + r.end(), outer_out[std::size_t(m)] + r.begin());
    }
    for (int v = r.begin(); v != r.end(); ++v) {
      const std::size_t o = std::size_t(outer[v]);
      const int n = outer[v + 1] - outer[v];
      std::array<double*, Count> col;
      const bool on_stack = n <= kStack;
      for (int m = 0; m < Count; ++m) {
        col[std::size_t(m)] = on_stack ? acc[m] : val[std::size_t(m)] + o;
        std::fill_n(col[std::size_t(m)], n, 0.0);
      }
      for (int a = vstart[v]; a < vstart[v + 1]; ++a) {
        const int c = vcorner[a];
        kernel(c >> 2, c & 3, rows);
        const std::uint16_t* s = slot + 4 * std::size_t(a);
        for (int j = 0; j < 4; ++j)
          for (int m = 0; m < Count; ++m) col[std::size_t(m)][s[j]] += rows[4 * m + j];
      }
      finish(v, col, n);
      if (on_stack)
        for (int m = 0; m < Count; ++m) std::copy_n(acc[m], n, val[std::size_t(m)] + o);
    }
  });
  outer_out[0][V] = int(nnz);
  for (int m = 1; m < Count; ++m) outer_out[std::size_t(m)][V] = int(nnz);
}

template <int Count, class RowKernel>
void gather_quad_rows(const QuadVertexPattern& p, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out) {
  if constexpr (Count == 2) {
    // A column holds at most 4 rows per incident face plus the diagonal.
    if (4 * p.vc.max_degree + 1 <= kPairColumnMax) return gather_quad_row_pairs(p, kernel, *out[0], *out[1]);
  }
  gather_quad_rows<Count>(p, kernel, out, NoColumnFinish{});
}

/// Vertex gather through the pattern when there is one, else the direct gather (same bits).
template <int Count, class RowKernel>
void gather_quad_rows(const SurfelMesh& mesh, const QuadVertexPattern* pat, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out) {
  if (pat)
    gather_quad_rows<Count>(*pat, kernel, out);
  else
    gather_quad_rows<Count>(mesh, vc, kernel, out);
}
template <int Count, class RowKernel, class ColumnFinish>
void gather_quad_rows(const SurfelMesh& mesh, const QuadVertexPattern* pat, const VertexCorners& vc, RowKernel&& kernel,
                      const std::array<Eigen::SparseMatrix<double>*, Count>& out, ColumnFinish&& finish) {
  if (pat)
    gather_quad_rows<Count>(*pat, kernel, out, finish);
  else
    gather_quad_rows<Count>(mesh, vc, kernel, out, finish);
}

/// Diagonal n x n matrix with entry r = diagonal_value(r), the entries computed in parallel.
template <class DiagonalValue>
Eigen::SparseMatrix<double> parallel_diagonal(int n, DiagonalValue&& diagonal_value) {
  Eigen::SparseMatrix<double> D(n, n);
  D.resizeNonZeros(n);
  int* outer = D.outerIndexPtr();
  int* inner = D.innerIndexPtr();
  double* val = D.valuePtr();
  outer[n] = n;
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 8192), [&](const tbb::blocked_range<int>& r) {
    for (int v = r.begin(); v != r.end(); ++v) {
      outer[v] = v;
      inner[v] = v;
      val[v] = diagonal_value(v);
    }
  });
  return D;
}

/// Diagonal matrix of the row sums of A, for A with a structurally symmetric pattern (every
/// vertex-based quad assembly): bitwise the sequential column-major scan d[row] += value (each
/// row summed over ascending columns, from +0.0), but parallel over rows: row r's columns are the
/// rows of column r, and A(r, c) is found by binary search in column c.
inline Eigen::SparseMatrix<double> row_sum_diagonal_symmetric(const Eigen::SparseMatrix<double>& A) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* values = A.valuePtr();
  return parallel_diagonal(int(A.rows()), [&](int r) {
    double s = 0.0;
    for (int a = outer[r]; a < outer[r + 1]; ++a) {
      const int c = inner[a];
      s += values[std::lower_bound(inner + outer[c], inner + outer[c + 1], r) - inner];
    }
    return s;
  });
}

/// Diagonal matrix with entry v = sum over the corners (f, i) at v, ascending f, of value(f, i).
template <class CornerValue>
Eigen::SparseMatrix<double> gather_corner_diagonal(const SurfelMesh& mesh, const VertexCorners& vc,
                                                   CornerValue&& value) {
  return parallel_diagonal(mesh.num_vertices(), [&](int v) {
    double s = 0.0;
    for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
      const int c = vc.corner[std::size_t(a)];
      s += value(c >> 2, c & 3);
    }
    return s;
  });
}

}  // namespace corrlap::detail
