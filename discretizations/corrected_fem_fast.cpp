// Bitwise equal to corrected_fem_local_frame, corrected_fem_local_stiffness and corrected_fem_local_mass, checked by
// TEST_CASE("fem fast face values and assembly are bitwise the readable local matrices").
//
// The assembly hot path of the corrected FEM (docs/math.md §4.2-§4.4): per face, one SIMD lane per face,
// the distinct values of K_f and the mass scales (the readable functions' operations in their
// order, no FMA contraction: -ffp-contract=off), then the fused row kernel + vertex gather.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <corrlap/discretizations/assembly/detail/avx2_target.inc>
#include <corrlap/discretizations/assembly/detail/quad_pattern_access.hpp>
#include <corrlap/discretizations/detail/fem_kernel.hpp>
#include <corrlap/discretizations/quad_assembly.hpp>
#include <cstring>

namespace corrlap::detail {

namespace {

typedef double FemLanes1 __attribute__((vector_size(8)));
typedef double FemLanes2 __attribute__((vector_size(16)));
typedef double FemLanes4 __attribute__((vector_size(32)));

// Faces f0 .. f0 + N - 1, one per lane of `vec`, into out + kFemFaceValues l: (self, o1, o2, o,
// s2, oe) of corrected_fem_local_stiffness and the mass scales area z / 36, area z / 4.
template <class vec>
__attribute__((always_inline)) inline void fem_face_batch(const double* P, std::size_t V, const int* faces,
                                                          const double* U, std::size_t F, std::size_t f0, double* out) {
  constexpr int N = int(sizeof(vec) / sizeof(double));
  double lanes[4][3][N];  // corners 0, 1, 3 and the normal, gathered lane by lane
  for (int l = 0; l < N; ++l) {
    const int* q = faces + 4 * (f0 + std::size_t(l));
    const int c[3] = {q[0], q[1], q[3]};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) lanes[k][d][l] = P[std::size_t(d) * V + std::size_t(c[k])];
    for (int d = 0; d < 3; ++d) lanes[3][d][l] = U[std::size_t(d) * F + f0 + std::size_t(l)];
  }
  vec x[4][3];
  std::memcpy(x, lanes, sizeof x);
  // Frame (docs/math.md §4.2): a = x1 - x0, b = x3 - x0, c = a x b, area = |c|.
  const vec ax = x[1][0] - x[0][0], ay = x[1][1] - x[0][1], az = x[1][2] - x[0][2];
  const vec bx = x[2][0] - x[0][0], by = x[2][1] - x[0][1], bz = x[2][2] - x[0][2];
  const vec cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const vec ux = x[3][0], uy = x[3][1], uz = x[3][2];
  const vec a2 = cx * cx + cy * cy + cz * cz, na2 = ax * ax + ay * ay + az * az, nb2 = bx * bx + by * by + bz * bz;
  vec area, na, nb;
  for (int l = 0; l < N; ++l) {
    area[l] = std::sqrt(a2[l]);
    na[l] = na2[l] > 0.0 ? std::sqrt(na2[l]) : 1.0;  // 1: a zero edge is left as is (exact division)
    nb[l] = nb2[l] > 0.0 ? std::sqrt(nb2[l]) : 1.0;
  }
  const vec gx = ux * (ax / na) + uy * (ay / na) + uz * (az / na);
  const vec gy = ux * (bx / nb) + uy * (by / nb) + uz * (bz / nb);
  const vec gz = ux * (cx / area) + uy * (cy / area) + uz * (cz / area);
  // Stiffness values (docs/math.md §4.3) and mass scales (docs/math.md §4.4).
  const vec iz = 1.0 / gz;
  const vec sx = 1.0 - gx * gx, sy = 1.0 - gy * gy, eta = gx * gy * 0.5 * iz;
  const vec self = eta + (sx + sy) / 3.0 * iz;
  const vec o1 = (-2.0 * sy + sx) / 6.0 * iz;
  const vec o2 = (-2.0 * sx + sy) / 6.0 * iz;
  const vec o = -eta - (sx + sy) / 6.0 * iz;
  const vec s2 = self - 2.0 * eta, oe = o + 2.0 * eta;
  const vec m36 = area * gz / 36.0, m4 = area * gz / 4.0;
  for (int l = 0; l < N; ++l) {
    double* g = out + std::size_t(l) * kFemFaceValues;
    g[0] = self[l], g[1] = o1[l], g[2] = o2[l], g[3] = o[l], g[4] = s2[l], g[5] = oe[l], g[6] = m36[l], g[7] = m4[l];
  }
}

template <class vec>
__attribute__((always_inline)) inline void fem_range_body(const double* P, std::size_t V, const int* faces,
                                                          const double* U, std::size_t F, int b, int e, double* g) {
  constexpr int N = int(sizeof(vec) / sizeof(double));
  int f = b;
  for (; f + N <= e; f += N)
    fem_face_batch<vec>(P, V, faces, U, F, std::size_t(f), g + std::size_t(f) * kFemFaceValues);
  for (; f < e; ++f) fem_face_batch<FemLanes1>(P, V, faces, U, F, std::size_t(f), g + std::size_t(f) * kFemFaceValues);
}

CORRLAP_AVX2_TARGET void fem_range_avx2(const double* P, std::size_t V, const int* faces, const double* U,
                                        std::size_t F, int b, int e, double* g) {
  fem_range_body<FemLanes4>(P, V, faces, U, F, b, e, g);
}
void fem_range_sse2(const double* P, std::size_t V, const int* faces, const double* U, std::size_t F, int b, int e,
                    double* g) {
  fem_range_body<FemLanes2>(P, V, faces, U, F, b, e, g);
}
void fem_range_scalar(const double* P, std::size_t V, const int* faces, const double* U, std::size_t F, int b, int e,
                      double* g) {
  fem_range_body<FemLanes1>(P, V, faces, U, F, b, e, g);
}

// Row i of L_f = -K_f from the values of fem_face_batch (the symmetric pattern of docs/math.md §4.3).
inline void fem_face_row(const double* g, int i, double* row) {
  const double self = g[0], o1 = g[1], o2 = g[2], o = g[3], s2 = g[4], oe = g[5];
  switch (i) {
    case 0:
      row[0] = -self, row[1] = -o1, row[2] = -o, row[3] = -o2;
      break;
    case 1:
      row[0] = -o1, row[1] = -s2, row[2] = -o2, row[3] = -oe;
      break;
    case 2:
      row[0] = -o, row[1] = -o2, row[2] = -self, row[3] = -o1;
      break;
    default:
      row[0] = -o2, row[1] = -oe, row[2] = -o1, row[3] = -s2;
      break;
  }
}

}  // namespace

void fem_face_range(const double* positions, std::size_t num_vertices, const int* faces, const double* normals,
                    std::size_t num_faces, int b, int e, double* g, FaceKernelIsa isa) {
  switch (resolve_face_kernel_isa(isa)) {
    case FaceKernelIsa::Avx2:
      return fem_range_avx2(positions, num_vertices, faces, normals, num_faces, b, e, g);
    case FaceKernelIsa::Sse2:
      return fem_range_sse2(positions, num_vertices, faces, normals, num_faces, b, e, g);
    default:
      return fem_range_scalar(positions, num_vertices, faces, normals, num_faces, b, e, g);
  }
}

void corrected_fem_fast_assembly(const SurfelMesh& mesh, const Eigen::MatrixX3d& u, const QuadPattern* pattern,
                                 bool lumped, bool with_lumped, Operators& ops) {
  const int F = mesh.num_faces();
  // Per face (x, y, z, area) -> the distinct values of its local matrices (docs/math.md §4.3, §4.4).
  constexpr std::size_t G = kFemFaceValues;
  PatternScratch geo(pattern, std::size_t(F) * G);
  tbb::parallel_for(tbb::blocked_range<int>(0, F, 2048), [&](const tbb::blocked_range<int>& r) {
    fem_face_range(mesh.positions.data(), std::size_t(mesh.num_vertices()), mesh.faces.data(), u.data(), std::size_t(F),
                   r.begin(), r.end(), geo.data());
  });
  // Fused kernel + vertex-row gather: the local matrices depend only on (x, y, z, area), so each
  // row is computed where it is summed and every matrix entry is written once (memory-bound).
  // Through the caller's pattern when given (quad_pattern.hpp), else the direct gather: same bits.
  const VertexGather gather(mesh, pattern, "fem");
  const QuadVertexPattern* pat = gather.pattern();
  const VertexCorners& vc = gather.vc();
  auto lumped_mass = [&] {
    return gather_corner_diagonal(mesh, vc, [&](int f, int) { return geo.data()[std::size_t(f) * G + 7]; });
  };
  auto stiffness = [&](int f, int i, double* rows) { fem_face_row(geo.data() + std::size_t(f) * G, i, rows); };
  auto stiffness_mass = [&](int f, int i, double* rows) {
    const double* g = geo.data() + std::size_t(f) * G;
    fem_face_row(g, i, rows);
    // docs/math.md §4.4 consistent mass row i: (area z / 36) [4 2 1 2] rotated.
    const double sc = g[6];
    static const double w[4] = {4, 2, 1, 2};
    for (int j = 0; j < 4; ++j) rows[4 + j] = sc * w[(j - i + 4) & 3];
  };
  if (lumped) {
    if (pat)
      gather_quad_rows<1>(*pat, stiffness, {&ops.L});
    else
      gather_quad_rows<1>(mesh, vc, stiffness, {&ops.L});
    ops.M = lumped_mass();
  } else {
    if (pat)
      gather_quad_rows<2>(*pat, stiffness_mass, {&ops.L, &ops.M});
    else
      gather_quad_rows<2>(mesh, vc, stiffness_mass, {&ops.L, &ops.M});
  }
  if (with_lumped) ops.M_lumped = lumped ? ops.M : lumped_mass();
}

}  // namespace corrlap::detail
