#include "corrected_fem.hpp"

#include <cmath>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <corrlap/core/error.hpp>

#include <corrlap/discretizations/assembly/detail/avx2_target.inc>
#include <corrlap/discretizations/detail/fem_kernel.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <corrlap/discretizations/assembly/detail/quad_row_gather.hpp>

namespace corrlap {

FemLocalFrame corrected_fem_local_frame(const QuadCorners& x, const Eigen::Vector3d& u) {
  // spec §4.2: e_s = normalize(x1 - x0), e_t = normalize(x3 - x0), nu = normalize(e1 x e3).
  const Eigen::Vector3d d1 = (x.row(1) - x.row(0)).transpose();
  const Eigen::Vector3d d3 = (x.row(3) - x.row(0)).transpose();
  const Eigen::Vector3d c = d1.cross(d3);
  FemLocalFrame fr;
  fr.area = c.norm();
  fr.u_local = Eigen::Vector3d(u.dot(d1.normalized()), u.dot(d3.normalized()), u.dot(c / fr.area));
  return fr;
}

namespace {
// corrected_fem_local_frame in scalar form, operation for operation (same roundings, so bitwise
// the same result), reading the column-major positions and
// normals directly (verified: full-precision L.mtx/M.mtx unchanged vs the Eigen form): no 4x3 corner copy, and the compiler can overlap the faces' sqrt/div chains.
inline void fem_geo(const double* P, std::size_t V, const int* q, const double* U, std::size_t F, std::size_t f,
                    double* g) {
  const double x0 = P[q[0]], y0 = P[V + q[0]], z0 = P[2 * V + q[0]];
  const double ax = P[q[1]] - x0, ay = P[V + q[1]] - y0, az = P[2 * V + q[1]] - z0;
  const double bx = P[q[3]] - x0, by = P[V + q[3]] - y0, bz = P[2 * V + q[3]] - z0;
  const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const double area = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double ux = U[f], uy = U[F + f], uz = U[2 * F + f];
  auto dot_normalized = [&](double x, double y, double z) {
    const double n2 = x * x + y * y + z * z;
    if (n2 > 0.0) {
      const double n = std::sqrt(n2);
      x = x / n, y = y / n, z = z / n;
    }
    return ux * x + uy * y + uz * z;
  };
  g[0] = dot_normalized(ax, ay, az);
  g[1] = dot_normalized(bx, by, bz);
  g[2] = ux * (cx / area) + uy * (cy / area) + uz * (cz / area);
  g[3] = area;
}

// Stiffness written straight into a row-major 4x4 buffer, scaled by `scale` (-1 for L_f).
inline void fem_stiffness_into(double x, double y, double z, double scale, double* K) {
  // spec §4.3, DGtal form (valid even when u is slightly off unit length).
  const double sx = 1.0 - x * x, sy = 1.0 - y * y, eta = x * y / (2.0 * z);
  const double self = eta + (sx + sy) / (3.0 * z);
  const double o1 = (-2.0 * sy + sx) / (6.0 * z);
  const double o2 = (-2.0 * sx + sy) / (6.0 * z);
  const double o = -eta - (sx + sy) / (6.0 * z);
  const double s2 = self - 2.0 * eta, oe = o + 2.0 * eta;
  const double v[16] = {self, o1, o, o2,  //
                        o1, s2, o2, oe,   //
                        o, o2, self, o1,  //
                        o2, oe, o1, s2};
  for (int k = 0; k < 16; ++k) K[k] = scale * v[k];
}

// Per face, once: the six distinct values of K_f (spec §4.3 pattern; the same expressions the
// reference-checked per-row kernel used, so the matrices are bitwise unchanged) and the mass scales area z / 36 and area z / 4
// (spec §4.4), from g = (x, y, z, area) in place; the divisions are then done once per face
// instead of once per incident vertex.
inline void fem_face_values(double* g) {
  const double x = g[0], y = g[1], z = g[2], area = g[3], iz = 1.0 / z;
  const double sx = 1.0 - x * x, sy = 1.0 - y * y, eta = x * y * 0.5 * iz;
  const double self = eta + (sx + sy) / 3.0 * iz;
  const double o1 = (-2.0 * sy + sx) / 6.0 * iz;
  const double o2 = (-2.0 * sx + sy) / 6.0 * iz;
  const double o = -eta - (sx + sy) / 6.0 * iz;
  g[0] = self, g[1] = o1, g[2] = o2, g[3] = o, g[4] = self - 2.0 * eta, g[5] = o + 2.0 * eta;
  g[6] = area * z / 36.0;
  g[7] = area * z / 4.0;
}

// Row i of L_f = -K_f from the values of fem_face_values.
inline void fem_face_row(const double* g, int i, double* row) {
  const double self = g[0], o1 = g[1], o2 = g[2], o = g[3], s2 = g[4], oe = g[5];
  switch (i) {
    case 0: row[0] = -self, row[1] = -o1, row[2] = -o, row[3] = -o2; break;
    case 1: row[0] = -o1, row[1] = -s2, row[2] = -o2, row[3] = -oe; break;
    case 2: row[0] = -o, row[1] = -o2, row[2] = -self, row[3] = -o1; break;
    default: row[0] = -o2, row[1] = -oe, row[2] = -o1, row[3] = -s2; break;
  }
}

inline void fem_mass_into(double area, double z, bool lumped, double* M) {
  if (lumped) {
    const double d = area * z / 4.0;
    for (int k = 0; k < 16; ++k) M[k] = (k % 5 == 0) ? d : 0.0;
    return;
  }
  static const double w[16] = {4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4};
  const double s = area * z / 36.0;
  for (int k = 0; k < 16; ++k) M[k] = s * w[k];
}

// fem_geo + fem_face_values for the N faces f0 .. f0 + N - 1, one per lane of `vec` (GCC vector
// extensions), with the scalar operations in the scalar order: same bits (nothing is contracted
// into FMAs, -ffp-contract=off). Square roots per lane in scalar code.
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
  const vec ax = x[1][0] - x[0][0], ay = x[1][1] - x[0][1], az = x[1][2] - x[0][2];
  const vec bx = x[2][0] - x[0][0], by = x[2][1] - x[0][1], bz = x[2][2] - x[0][2];
  const vec cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const vec ux = x[3][0], uy = x[3][1], uz = x[3][2];
  const vec a2 = cx * cx + cy * cy + cz * cz, na2 = ax * ax + ay * ay + az * az, nb2 = bx * bx + by * by + bz * bz;
  vec area, na, nb;
  for (int l = 0; l < N; ++l) {
    area[l] = std::sqrt(a2[l]);
    na[l] = na2[l] > 0.0 ? std::sqrt(na2[l]) : 1.0;  // 1: the scalar code leaves the vector as is
    nb[l] = nb2[l] > 0.0 ? std::sqrt(nb2[l]) : 1.0;
  }
  // Dividing by 1.0 is exact, so the lanes with a zero edge keep the scalar result.
  const vec gx = ux * (ax / na) + uy * (ay / na) + uz * (az / na);
  const vec gy = ux * (bx / nb) + uy * (by / nb) + uz * (bz / nb);
  const vec gz = ux * (cx / area) + uy * (cy / area) + uz * (cz / area);
  const vec iz = 1.0 / gz;
  const vec sx = 1.0 - gx * gx, sy = 1.0 - gy * gy, eta = gx * gy * 0.5 * iz;
  const vec self = eta + (sx + sy) / 3.0 * iz;
  const vec o1 = (-2.0 * sy + sx) / 6.0 * iz;
  const vec o2 = (-2.0 * sx + sy) / 6.0 * iz;
  const vec o = -eta - (sx + sy) / 6.0 * iz;
  const vec s2 = self - 2.0 * eta, oe = o + 2.0 * eta;
  const vec m36 = area * gz / 36.0, m4 = area * gz / 4.0;
  for (int l = 0; l < N; ++l) {
    double* g = out + std::size_t(l) * detail::kFemFaceValues;
    g[0] = self[l], g[1] = o1[l], g[2] = o2[l], g[3] = o[l], g[4] = s2[l], g[5] = oe[l], g[6] = m36[l], g[7] = m4[l];
  }
}

typedef double FemLanes2 __attribute__((vector_size(16)));
typedef double FemLanes4 __attribute__((vector_size(32)));

template <class vec>
__attribute__((always_inline)) inline void fem_range_body(const double* P, std::size_t V, const int* faces,
                                                          const double* U, std::size_t F, int b, int e, double* g) {
  constexpr int N = int(sizeof(vec) / sizeof(double));
  int f = b;
  if constexpr (N > 1)
    for (; f + N <= e; f += N) fem_face_batch<vec>(P, V, faces, U, F, std::size_t(f), g + std::size_t(f) * detail::kFemFaceValues);
  for (; f < e; ++f) {
    double* gf = g + std::size_t(f) * detail::kFemFaceValues;
    fem_geo(P, V, faces + 4 * std::size_t(f), U, F, std::size_t(f), gf);
    fem_face_values(gf);
  }
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
  fem_range_body<double>(P, V, faces, U, F, b, e, g);
}
}  // namespace

void detail::fem_face_range(const double* positions, std::size_t num_vertices, const int* faces,
                            const double* normals, std::size_t num_faces, int b, int e, double* g, FaceKernelIsa isa) {
  switch (resolve_face_kernel_isa(isa)) {
    case FaceKernelIsa::Avx2: return fem_range_avx2(positions, num_vertices, faces, normals, num_faces, b, e, g);
    case FaceKernelIsa::Sse2: return fem_range_sse2(positions, num_vertices, faces, normals, num_faces, b, e, g);
    default: return fem_range_scalar(positions, num_vertices, faces, normals, num_faces, b, e, g);
  }
}

Eigen::Matrix4d corrected_fem_local_stiffness(const Eigen::Vector3d& u) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> K;
  fem_stiffness_into(u.x(), u.y(), u.z(), 1.0, K.data());
  return K;
}

Eigen::Matrix4d corrected_fem_local_mass(double area, double z) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M;
  fem_mass_into(area, z, false, M.data());
  return M;
}

Eigen::Matrix4d corrected_fem_local_lumped_mass(double area, double z) {
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> M;
  fem_mass_into(area, z, true, M.data());
  return M;
}

namespace {

class CorrectedFem final : public Discretization {
 public:
  std::string name() const override { return "fem"; }
  NormalKind required_normals() const override { return NormalKind::Face; }
  std::vector<ParameterInfo> parameters() const override {
    std::vector<ParameterInfo> p = {{"mass", "full", "mass matrix: full (consistent) | lumped (diagonal), spec §4.4"},
                                    extras_parameter()};
    for (auto& q : normal_policy_parameters()) p.push_back(q);
    return p;
  }

  Operators assemble(const SurfelMesh& mesh, const NormalFields& normals, const Config& params) const override {
    Operators ops;
    assemble_into(mesh, normals, params, ops);
    return ops;
  }

  // L and M are filled by gather_quad_rows, whose resize keeps the matrices' allocated storage:
  // with a reused `ops` nothing is allocated for them.
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params,
                     Operators& ops) const override {
    params.check_parameters(parameters(), "fem parameters");
    const std::string mass = params.get_string("mass", "full");
    if (mass != "full" && mass != "lumped") throw InputError("fem: mass '" + mass + "': expected full or lumped");
    const bool extras = params.get_bool("extras", false);
    check_quad_mesh(mesh, "fem");

    reset_for_reuse(ops);
    const PreparedNormals prepared = prepare_normals(mesh, normals, NormalKind::Face, params, "fem", ops.warnings);
    const Eigen::MatrixX3d& u = prepared.matrix();
    const int F = mesh.num_faces();
    // Per face (x, y, z, area) -> the distinct values of its local matrices (spec §4.3, §4.4).
    constexpr std::size_t G = detail::kFemFaceValues;
    detail::ReusedScratch geo(std::size_t(F) * G);
    tbb::parallel_for(tbb::blocked_range<int>(0, F, 2048), [&](const tbb::blocked_range<int>& r) {
      detail::fem_face_range(mesh.positions.data(), std::size_t(mesh.num_vertices()), mesh.faces.data(), u.data(),
                             std::size_t(F), r.begin(), r.end(), geo.data());
    });
    // Fused kernel + vertex-row gather: the local matrices depend only on (x, y, z, area), so each
    // row is computed where it is summed and every matrix entry is written once (memory-bound).
    // Pattern cached per connectivity (quad_row_gather.hpp); direct gather if it cannot be cached.
    const auto pat = detail::quad_vertex_pattern(mesh);
    const detail::VertexCorners vc_direct = pat ? detail::VertexCorners{} : detail::vertex_corners(mesh);
    const detail::VertexCorners& vc = pat ? pat->vc : vc_direct;
    const bool lumped = mass == "lumped";
    auto lumped_mass = [&] {
      return detail::gather_corner_diagonal(mesh, vc, [&](int f, int) { return geo.data()[std::size_t(f) * G + 7]; });
    };
    auto stiffness = [&](int f, int i, double* rows) { fem_face_row(geo.data() + std::size_t(f) * G, i, rows); };
    auto stiffness_mass = [&](int f, int i, double* rows) {
      const double* g = geo.data() + std::size_t(f) * G;
      fem_face_row(g, i, rows);
      // spec §4.4 consistent mass row i: (area z / 36) [4 2 1 2] rotated.
      const double sc = g[6];
      static const double w[4] = {4, 2, 1, 2};
      for (int j = 0; j < 4; ++j) rows[4 + j] = sc * w[(j - i + 4) & 3];
    };
    if (lumped) {
      if (pat) detail::gather_quad_rows<1>(*pat, stiffness, {&ops.L});
      else detail::gather_quad_rows<1>(mesh, vc, stiffness, {&ops.L});
      ops.M = lumped_mass();
    } else {
      if (pat) detail::gather_quad_rows<2>(*pat, stiffness_mass, {&ops.L, &ops.M});
      else detail::gather_quad_rows<2>(mesh, vc, stiffness_mass, {&ops.L, &ops.M});
    }
    if (extras) {
      ops.M_lumped = lumped ? ops.M : lumped_mass();
      ops.D0 = global_d0(build_edges(mesh), mesh.num_vertices());
    }
  }
};

}  // namespace

std::unique_ptr<Discretization> make_corrected_fem() { return std::make_unique<CorrectedFem>(); }

}  // namespace corrlap
