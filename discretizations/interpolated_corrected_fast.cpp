// Bitwise equal to interpolated_local (mass, sharp_stiffness, projected_difference, laplacian), checked by
// TEST_CASE("interpolated fast face terms are bitwise the readable interpolated_local").
//
// The per-face kernel of the interpolated corrected calculus (docs/math.md §3.2-§3.5) for the assembly hot
// loop: several faces per SIMD register (one face per lane), each lane doing the readable
// function's operations in its order (no FMA contraction: -ffp-contract=off), writing only what the
// assembly reads; then the global (docs/math.md §3.6a) or local (§3.6b) assembly of L and M.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/assembly/detail/avx2_target.inc>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>
#include <corrlap/discretizations/detail/interpolated_kernel.hpp>
#include <cstddef>
#include <cstring>
#include <string>

namespace corrlap::detail {

namespace {

typedef double Lanes1 __attribute__((vector_size(8)));   // one face: the tail of a range
typedef double Lanes2 __attribute__((vector_size(16)));  // an SSE2 register of doubles
typedef double Lanes4 __attribute__((vector_size(32)));  // an AVX register of doubles

// a . b for 3-vectors of lanes, summed left to right as the scalar dot (a macro: a helper
// function returning an AVX vector would be compiled for the default target).
#define CORRLAP_DOT3(a, b) ((a)[0] * (b)[0] + (a)[1] * (b)[1] + (a)[2] * (b)[2])

// The records of N consecutive faces f0 .. f0 + N - 1 at once, one face per vector lane (GCC
// vector extensions: compiled as AVX2, SSE2 or scalar code by the caller's target); square roots
// and the square test (to 1e-6) per lane in scalar code.
// Corners come from `faces` (4 per face), positions px/py/pz and normals ux/uy/uz (one array per
// component). Returns false, having written nothing, when some face is not a square.

template <class vec>
__attribute__((always_inline)) inline bool interpolated_face_terms_batch(const int* faces, int f0, const double* px,
                                                                         const double* py, const double* pz,
                                                                         const double* ux, const double* uy,
                                                                         const double* uz_, double kappa, double* terms,
                                                                         double* pd) {
  constexpr int N = int(sizeof(vec) / sizeof(double));
  double xl[4][3][N], ulanes[4][3][N];  // gathered lane by lane, then loaded as vectors
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < N; ++l) {
      const int v = faces[4 * (f0 + l) + k];
      xl[k][0][l] = px[v];
      xl[k][1][l] = py[v];
      xl[k][2][l] = pz[v];
      ulanes[k][0][l] = ux[v];
      ulanes[k][1][l] = uy[v];
      ulanes[k][2][l] = uz_[v];
    }
  vec x[4][3], u[4][3];
  std::memcpy(x, xl, sizeof x);
  std::memcpy(u, ulanes, sizeof u);
  vec e[4][3];
  for (int i = 0; i < 4; ++i)
    for (int c = 0; c < 3; ++c) e[i][c] = x[(i + 1) & 3][c] - x[i][c];
  const vec q0 = CORRLAP_DOT3(e[0], e[0]), q1 = CORRLAP_DOT3(e[1], e[1]), d01 = CORRLAP_DOT3(e[0], e[1]);
  const vec s02[3] = {e[0][0] + e[2][0], e[0][1] + e[2][1], e[0][2] + e[2][2]};
  const vec q02 = CORRLAP_DOT3(s02, s02);
  vec l0, l1;
  for (int l = 0; l < N; ++l) {
    l0[l] = std::sqrt(q0[l]);
    l1[l] = std::sqrt(q1[l]);
    if (!(std::abs(l1[l] - l0[l]) <= 1e-6 * l0[l] && std::abs(d01[l]) <= 1e-6 * l0[l] * l0[l] &&
          std::sqrt(q02[l]) <= 1e-6 * l0[l]))
      return false;
  }
  const vec h = l0;
  const vec ih = 1.0 / h, il1 = 1.0 / l1;
  const vec t1[3] = {e[0][0] * ih, e[0][1] * ih, e[0][2] * ih};
  const vec t2[3] = {e[1][0] * il1, e[1][1] * il1, e[1][2] * il1};
  const vec n[3] = {t1[1] * t2[2] - t1[2] * t2[1], t1[2] * t2[0] - t1[0] * t2[2], t1[0] * t2[1] - t1[1] * t2[0]};
  vec ul[4][3];
  for (int k = 0; k < 4; ++k) {
    ul[k][0] = CORRLAP_DOT3(u[k], t1);
    ul[k][1] = CORRLAP_DOT3(u[k], t2);
    ul[k][2] = CORRLAP_DOT3(u[k], n);
  }
  vec ue[4][3], ub[3];
  for (int c = 0; c < 3; ++c) {
    for (int i = 0; i < 4; ++i) ue[i][c] = 0.5 * (ul[i][c] + ul[(i + 1) & 3][c]);
    ub[c] = 0.25 * (ul[0][c] + ul[1][c] + ul[2][c] + ul[3][c]);
  }
  const vec uz = ub[2];
  constexpr double s6 = 1.0 / 6.0;
  const vec zero = {};  // the literal zeros of the scalar S
  const vec S[3][4] = {{(2.0 * uz + ue[0][2]) * s6, zero, -(2.0 * uz + ue[2][2]) * s6, zero},
                       {zero, (2.0 * uz + ue[1][2]) * s6, zero, -(2.0 * uz + ue[3][2]) * s6},
                       {-(2.0 * ub[0] + ue[0][0]) * s6, -(2.0 * ub[1] + ue[1][1]) * s6, (2.0 * ub[0] + ue[2][0]) * s6,
                        (2.0 * ub[1] + ue[3][1]) * s6}};
  vec G[3][4];
  for (int c = 0; c < 3; ++c)
    for (int j = 0; j < 4; ++j) G[c][j] = S[c][(j + 3) & 3] - S[c][j];
  const vec iuz = 1.0 / uz;
  vec k1[10];
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) k1[kSym[i][j]] = (G[0][i] * G[0][j] + G[1][i] * G[1][j] + G[2][i] * G[2][j]) * iuz;
  const vec w = ih * iuz;
  const double kk = kappa * s6;
  vec p[16];
  for (int i = 0; i < 4; ++i) {
    const vec* ua = u[i];
    const vec* ubv = u[(i + 1) & 3];
    const vec da = CORRLAP_DOT3(e[i], ua), db = CORRLAP_DOT3(e[i], ubv);
    const vec ca = kk * (2.0 * da + db), cb = kk * (da + 2.0 * db);
    const vec v[3] = {e[i][0] - ca * ua[0] - cb * ubv[0], e[i][1] - ca * ua[1] - cb * ubv[1],
                      e[i][2] - ca * ua[2] - cb * ubv[2]};
    const vec vr0 = CORRLAP_DOT3(v, t1) * w, vr1 = CORRLAP_DOT3(v, t2) * w, vr2 = CORRLAP_DOT3(v, n) * w;
    for (int j = 0; j < 4; ++j) p[4 * i + j] = -(vr0 * G[0][j] + vr1 * G[1][j] + vr2 * G[2][j]);
    p[4 * i + i] -= 1.0;
    p[4 * i + ((i + 1) & 3)] += 1.0;
  }
  const vec hh = h * h / 144.0;
  for (int l = 0; l < N; ++l) {
    double* t = terms + std::size_t(l) * kTermsStride;
    double* o = pd + std::size_t(l) * 16;
    for (int k = 0; k < 4; ++k) t[k] = ul[k][2][l];
    t[4] = hh[l];
    for (int m = 0; m < 10; ++m) t[kTermsK1 + m] = k1[m][l];
    for (int m = 0; m < 16; ++m) o[m] = p[m][l];
  }
  return true;
}

#undef CORRLAP_DOT3

template <class Lanes>
__attribute__((always_inline)) inline int face_range_body(const int* faces, int b, int e, const double* const x[3],
                                                          const double* const u[3], double kappa, double* terms,
                                                          double* pd) {
  constexpr int N = int(sizeof(Lanes) / sizeof(double));
  int f = b;
  if constexpr (N > 1)
    for (; f + N <= e; f += N)
      if (!interpolated_face_terms_batch<Lanes>(faces, f, x[0], x[1], x[2], u[0], u[1], u[2], kappa,
                                                terms + std::size_t(f) * kTermsStride, pd + std::size_t(f) * 16))
        break;  // some face of the batch is not a square: the one-face loop finds which
  for (; f < e; ++f)
    if (!interpolated_face_terms_batch<Lanes1>(faces, f, x[0], x[1], x[2], u[0], u[1], u[2], kappa,
                                               terms + std::size_t(f) * kTermsStride, pd + std::size_t(f) * 16))
      return f;
  return -1;
}

CORRLAP_AVX2_TARGET int face_range_avx2(const int* faces, int b, int e, const double* const x[3],
                                        const double* const u[3], double kappa, double* terms, double* pd) {
  return face_range_body<Lanes4>(faces, b, e, x, u, kappa, terms, pd);
}

int face_range_sse2(const int* faces, int b, int e, const double* const x[3], const double* const u[3], double kappa,
                    double* terms, double* pd) {
  return face_range_body<Lanes2>(faces, b, e, x, u, kappa, terms, pd);
}

int face_range_scalar(const int* faces, int b, int e, const double* const x[3], const double* const u[3], double kappa,
                      double* terms, double* pd) {
  return face_range_body<Lanes1>(faces, b, e, x, u, kappa, terms, pd);
}

}  // namespace

int interpolated_face_range(const int* faces, int b, int e, const double* const position[3],
                            const double* const normal[3], double kappa, double* terms, double* pd, FaceKernelIsa isa) {
  switch (resolve_face_kernel_isa(isa)) {
    case FaceKernelIsa::Avx2:
      return face_range_avx2(faces, b, e, position, normal, kappa, terms, pd);
    case FaceKernelIsa::Sse2:
      return face_range_sse2(faces, b, e, position, normal, kappa, terms, pd);
    default:
      return face_range_scalar(faces, b, e, position, normal, kappa, terms, pd);
  }
}

namespace {

// Sized output with the given column structure (values uninitialized; the fill writes them all).
void allocate_like(Eigen::SparseMatrix<double>& A, int V, const int* outer) {
  size_for_fill(A, V, outer[V]);
  std::copy(outer, outer + V + 1, A.outerIndexPtr());
}

// docs/math.md §3.6a: L = -D0^T (U^T C_A U + lambda P^T P) D0. Row e of P D0 is
// r_e = (1/n_e) sum_{f ni e} s_{f,i} (P_f D)[i, :] on the vertices of f, so
// L = -sum_f D^T (S^T S / ubar^z) D - lambda sum_e r_e r_e^T. Assembled by vertex columns: column v
// sums the face terms of its faces (incidences ascending) and then lambda r_e[v] r_e over the
// edges of its faces (ascending), so the result is the same for any thread count.
// `faceterms` holds the per-face records of interpolated_face_range; `r` the edge rows (k per edge).
// When `mpat` is given, M (docs/math.md §3.2, M = sum_f M0_f) is filled in the same column pass, with the
// same summation order as gather_quad_rows.
template <class Pos>
void fill_columns(const ProjectionPattern& pp, const VertexCorners& vc, const QuadVertexPattern* mpat,
                  const double* faceterms, const double* r, double lambda, const Pos* face_pos, const Pos* ce_pos,
                  Eigen::SparseMatrix<double>& L, Eigen::SparseMatrix<double>* M) {
  const int V = int(vc.start.size()) - 1, k = pp.k;
  const int* outer = pp.outer.data();
  const int* pin = pp.inner.data();
  int* inner = L.innerIndexPtr();
  double* val = L.valuePtr();
  const int* vstart = vc.start.data();
  const int* vcorner = vc.corner.data();
  const int* ce_start = pp.ce_start.data();
  const int* ce_edge = pp.ce_edge.data();
  const std::uint8_t* ce_sv = pp.ce_sv.data();
  const std::uint8_t* esize = pp.size.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, V, 1024), [&](const tbb::blocked_range<int>& range) {
    // Rows and zeroed values of the whole block first (sequential streams), then accumulation.
    const std::size_t b = std::size_t(outer[range.begin()]), e = std::size_t(outer[range.end()]);
    std::copy(pin + b, pin + e, inner + b);
    std::fill(val + b, val + e, 0.0);
    const int* mouter = nullptr;
    double* mval = nullptr;
    const std::uint16_t* mslot = nullptr;
    if (M) {
      mouter = mpat->outer.data();
      mval = M->valuePtr();
      mslot = mpat->slot.data();
      const std::size_t mb = std::size_t(mouter[range.begin()]), me = std::size_t(mouter[range.end()]);
      std::copy(mpat->inner.data() + mb, mpat->inner.data() + me, M->innerIndexPtr() + mb);
      std::fill(mval + mb, mval + me, 0.0);
    }
    constexpr int ahead = 2;  // columns: the edge rows and face records are scattered in memory
    for (int v = range.begin(); v != range.end(); ++v) {
      if (v + ahead < V) {
        for (int q = ce_start[v + ahead]; q < ce_start[v + ahead + 1]; ++q)
          __builtin_prefetch(r + std::size_t(ce_edge[q]) * std::size_t(k));
        for (int a = vstart[v + ahead]; a < vstart[v + ahead + 1]; ++a)
          __builtin_prefetch(faceterms + std::size_t(vcorner[a] >> 2) * kTermsStride);
      }
      double* col = val + outer[v];
      double* mcol = M ? mval + mouter[v] : nullptr;
      for (int a = vstart[v]; a < vstart[v + 1]; ++a) {
        const int c = vcorner[a];
        const double* t = faceterms + std::size_t(c >> 2) * kTermsStride;
        const int i = c & 3;
        const Pos* fp = face_pos + 4 * std::size_t(a);
        for (int j = 0; j < 4; ++j) col[fp[j]] -= t[kTermsK1 + kSym[i][j]];
        if (mcol) {
          double row[4];
          interpolated_mass_row(t, i, row);
          const std::uint16_t* ms = mslot + 4 * std::size_t(a);
          for (int j = 0; j < 4; ++j) mcol[ms[j]] += row[j];
        }
      }
      for (int q = ce_start[v]; q < ce_start[v + 1]; ++q) {
        const std::size_t ed = std::size_t(ce_edge[q]);
        const double* re = r + ed * std::size_t(k);
        const double a = lambda * re[ce_sv[q]];
        if (a == 0.0) continue;
        const Pos* cp = ce_pos + std::size_t(q) * std::size_t(k);
        const int n = esize[ed];
        for (int s = 0; s < n; ++s) col[cp[s]] -= a * re[s];
      }
    }
  });
}

// Rows r_e of P D0 (docs/math.md §3.6a), one per edge, on the element slots: sum over the incidences in
// face order of s_{f,i} / n_e (P_f D)[i, :]. `pd` holds P_f D per face (row-major 4x4).
// The second face of an edge is often far from the first in face order (docs/math.md §1.4 sorts by
// orientation first), so its row is a cache miss: it is prefetched 16 edges ahead (bench/RESULTS.md,
// "Assembly: record of experiments").
void edge_rows(const ProjectionPattern& pp, const double* pd, double* r) {
  const int k = pp.k, E = pp.num_edges;
  const int* inc_start = pp.inc_start.data();
  const int* inc_row = pp.inc_row.data();
  const double* inc_coef = pp.inc_coef.data();
  const std::uint8_t* inc_slot = pp.inc_slot.data();
  const std::uint8_t* size = pp.size.data();
  tbb::parallel_for(tbb::blocked_range<int>(0, E, 4096), [&](const tbb::blocked_range<int>& range) {
    constexpr int ahead = 16;
    for (int e = range.begin(); e != range.end(); ++e) {
      if (e + ahead < E)
        for (int a = inc_start[e + ahead]; a < inc_start[e + ahead + 1]; ++a)
          __builtin_prefetch(pd + 4 * std::size_t(inc_row[a]));
      double* re = r + std::size_t(e) * std::size_t(k);
      for (int s = 0; s < size[e]; ++s) re[s] = 0.0;
      for (int a = inc_start[e]; a < inc_start[e + 1]; ++a) {
        const double* row = pd + 4 * std::size_t(inc_row[a]);
        const std::uint8_t* slot = inc_slot + 4 * std::size_t(a);
        const double coef = inc_coef[a];
        for (int j = 0; j < 4; ++j) re[slot[j]] += coef * row[j];
      }
    }
  });
}

}  // namespace

void interpolated_fast_assembly(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, const QuadPattern* pattern,
                                double lambda, double kappa, bool global, Operators& ops) {
  const int F = mesh.num_faces();
  const VertexGather gather(mesh, pattern, "interpolated");
  const QuadVertexPattern* pat = gather.pattern();
  const VertexCorners& vc = gather.vc();
  // The projection structure (docs/math.md §3.6a): the pattern's (built on its first use), else built
  // for this assembly.
  std::unique_ptr<ProjectionPattern> own_pp;
  const ProjectionPattern* pp = nullptr;
  if (global) {
    if (pattern)
      pp = &projection_pattern(*pattern);
    else
      pp = (own_pp = build_projection_pattern(mesh.faces.data(), F, vc)).get();
  }
  // One reused buffer (no first-touch page faults in steady state; every read entry is
  // written first): the face records of interpolated_face_range (local assembly: L_f packed in
  // place of K1), P_f D per face, then the edge rows r_e (k per edge, global).
  const std::size_t pd_off = std::size_t(F) * kTermsStride, r_off = pd_off + std::size_t(F) * 16;
  PatternScratch data(pattern, r_off + (global ? std::size_t(pp->num_edges) * std::size_t(pp->k) : 0));
  double* terms = data.data();
  double* pdata = data.data() + pd_off;
  const double* px = mesh.positions.col(0).data();
  const double* py = mesh.positions.col(1).data();
  const double* pz = mesh.positions.col(2).data();
  const int* faces = mesh.faces.data();
  std::atomic<int> non_square{-1};
  const double* const xc[3] = {px, py, pz};
  const double* const uc[3] = {u.col(0).data(), u.col(1).data(), u.col(2).data()};
  tbb::parallel_for(tbb::blocked_range<int>(0, F, 1024), [&](const tbb::blocked_range<int>& r) {
    // The closed forms of docs/math.md §3.2-§3.4 hold on surfels (squares); other quads are rejected.
    const int bad = interpolated_face_range(faces, r.begin(), r.end(), xc, uc, kappa, terms, pdata);
    if (bad >= 0) {
      int cur = non_square.load();
      while ((cur < 0 || bad < cur) && !non_square.compare_exchange_weak(cur, bad)) {
      }
      return;
    }
    if (!global)
      for (int f = r.begin(); f != r.end(); ++f) {
        // L_f = -D^T M1 D = -(K1 + lambda (P D)^T (P D)) (docs/math.md §3.5), packed like K1.
        double* t = terms + std::size_t(f) * kTermsStride;
        const double* pd = pdata + std::size_t(f) * 16;
        for (int i = 0; i < 4; ++i)
          for (int j = i; j < 4; ++j) {
            double s = 0.0;
            for (int m = 0; m < 4; ++m) s += pd[4 * m + i] * pd[4 * m + j];
            double& k = t[kTermsK1 + kSym[i][j]];
            k = -(k + lambda * s);
          }
      }
  });
  if (non_square.load() >= 0)
    throw InputError("interpolated: face " + std::to_string(non_square.load()) +
                     " is not a square; the interpolated corrected calculus needs a mesh of surfels (docs/math.md §3)");
  if (global) {
    double* r = data.data() + r_off;
    edge_rows(*pp, pdata, r);
    allocate_like(ops.L, mesh.num_vertices(), pp->outer.data());
    if (pat)
      allocate_like(ops.M, mesh.num_vertices(), pat->outer.data());
    else
      gather_quad_rows<1>(
          mesh, nullptr, vc,
          [&](int f, int i, double* row) { interpolated_mass_row(terms + std::size_t(f) * kTermsStride, i, row); },
          {&ops.M});
    Eigen::SparseMatrix<double>* M = pat ? &ops.M : nullptr;
    if (pp->wide)
      fill_columns<int>(*pp, vc, pat, terms, r, lambda, pp->face_pos32.data(), pp->ce_pos32.data(), ops.L, M);
    else
      fill_columns<std::uint8_t>(*pp, vc, pat, terms, r, lambda, pp->face_pos8.data(), pp->ce_pos8.data(), ops.L, M);
  } else {
    gather_quad_rows<2>(mesh, pat, vc,
                        [&](int f, int i, double* rows) {
                          const double* t = terms + std::size_t(f) * kTermsStride;
                          interpolated_mass_row(t, i, rows);
                          for (int j = 0; j < 4; ++j) rows[4 + j] = t[kTermsK1 + kSym[i][j]];
                        },
                        {&ops.M, &ops.L});
  }
}

}  // namespace corrlap::detail
