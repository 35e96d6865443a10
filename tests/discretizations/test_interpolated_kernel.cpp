// The fast face kernel of the interpolated corrected calculus (interpolated_corrected_fast.cpp)
// computes M_{0,f}, D^T (S^T S / ubar^z) D and P_f D bit for bit as the readable interpolated_local()
// (docs/math.md §3.2-§3.5), for squares of any orientation and size and on surfel meshes, for every ISA.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/assembly/detail/quad_row_gather.hpp>
#include <corrlap/discretizations/detail/interpolated_kernel.hpp>
#include <corrlap/discretizations/interpolated_corrected.hpp>
#include <cstring>
#include <random>
#include <vector>

#include "reference_support.hpp"

using namespace corrlap;

namespace {

struct KernelCase {
  QuadCorners x, u;
};

// A square of side h with a random rotation and offset (or an axis-aligned surfel), and unit
// corner normals tilted randomly around its normal.
KernelCase random_case(std::mt19937& rng, bool axis_aligned) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::normal_distribution<double> g;
  const double h = std::pow(10.0, -2.5 * (uni(rng) + 1.0) / 2.0);  // 1 .. 0.003
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (!axis_aligned)
    R = Eigen::Quaterniond(Eigen::Vector4d(g(rng), g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
  else {
    // a signed permutation: any of the 6 surfel orientations
    const int a = int(rng() % 3);
    const Eigen::Vector3d e0 = Eigen::Vector3d::Unit(a) * (rng() % 2 ? 1.0 : -1.0);
    const int b = (a + 1 + int(rng() % 2)) % 3;  // cyclic or anti-cyclic pair of axes
    const Eigen::Vector3d e1 = Eigen::Vector3d::Unit(b) * (rng() % 2 ? 1.0 : -1.0);
    R.col(0) = e0;
    R.col(1) = e1;
    R.col(2) = e0.cross(e1);
  }
  const Eigen::Vector3d o(uni(rng), uni(rng), uni(rng));
  const double corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  KernelCase c;
  for (int k = 0; k < 4; ++k) {
    c.x.row(k) = (o + h * (corners[k][0] * R.col(0) + corners[k][1] * R.col(1))).transpose();
    const Eigen::Vector3d n = (R.col(2) + 0.5 * Eigen::Vector3d(g(rng), g(rng), g(rng))).normalized();
    c.u.row(k) = n.transpose();
  }
  return c;
}

double max_abs(const Eigen::Matrix4d& a) { return a.cwiseAbs().maxCoeff(); }

// The fast record of one quad (corners x, corner normals u) through interpolated_face_range.
bool face_terms(const QuadCorners& x, const QuadCorners& u, double kappa, double* terms, double* pd,
                detail::FaceKernelIsa isa = detail::FaceKernelIsa::Scalar) {
  const int faces[4] = {0, 1, 2, 3};
  double xs[3][4], us[3][4];
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) xs[c][k] = x(k, c), us[c][k] = u(k, c);
  const double* xp[3] = {xs[0], xs[1], xs[2]};
  const double* up[3] = {us[0], us[1], us[2]};
  return detail::interpolated_face_range(faces, 0, 1, xp, up, kappa, terms, pd, isa) < 0;
}

// The readable matrices of the record: M_{0,f}, K1 (sharp_stiffness), P_f D.
void unpack(const double* terms, const double* pd, Eigen::Matrix4d& M, Eigen::Matrix4d& K1, Eigen::Matrix4d& PD) {
  for (int i = 0; i < 4; ++i) {
    double row[4];
    detail::interpolated_mass_row(terms, i, row);
    for (int j = 0; j < 4; ++j) {
      M(i, j) = row[j];
      K1(i, j) = terms[detail::kTermsK1 + detail::kSym[i][j]];
      PD(i, j) = pd[4 * i + j];
    }
  }
}

bool same_bits(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * 16) == 0;
}

}  // namespace

TEST_CASE("interpolated assembly kernel on random squares: bitwise interpolated_local, which is docs/math.md §3.5") {
  std::mt19937 rng(11);
  const Eigen::Matrix4d& D = quad_difference();
  for (int trial = 0; trial < 400; ++trial) {
    const bool axis = trial % 2 == 0;
    const KernelCase c = random_case(rng, axis);
    const double kappa = trial % 3 == 0 ? 1.0 : 2.0;
    const InterpolatedLocal ref = interpolated_local(c.x, c.u, 0.1, kappa);
    double terms[detail::kTermsStride], pd[16];
    REQUIRE(face_terms(c.x, c.u, kappa, terms, pd));
    Eigen::Matrix4d M, K1, PD;
    unpack(terms, pd, M, K1, PD);
    INFO("trial " << trial << (axis ? " (axis-aligned)" : " (rotated)"));
    CHECK(same_bits(M, ref.mass));
    CHECK(same_bits(K1, ref.sharp_stiffness));
    CHECK(same_bits(PD, ref.projected_difference));
    // The readable quantities are those of docs/math.md §3.5 written with D: D^T (S^T S / ubar^z) D, P_f D
    // and L_f = -D^T M_{1,f} D, to round-off.
    const Eigen::Matrix4d K1_spec = D.transpose() * (ref.S.transpose() * ref.S / ref.ubar_z) * D;
    CHECK(max_abs(K1 - K1_spec) <= 1e-13 * max_abs(K1_spec));
    CHECK(max_abs(PD - ref.projection * D) <= 1e-13 * max_abs(PD));
    const Eigen::Matrix4d L_spec = -D.transpose() * ref.inner_product * D;
    CHECK(max_abs(ref.laplacian - L_spec) <= 1e-13 * max_abs(L_spec));
  }
}

TEST_CASE("interpolated fast face terms are bitwise the readable interpolated_local") {
  const std::vector<detail::FaceKernelIsa> isas = test::face_kernel_isas();
  for (const char* shape : {"sphere1", "torus"})
    for (bool perturbed : {false, true}) {
      const test::SphereCase s = test::shape_case(shape, shape == std::string("torus") ? 0.5 : 0.125, perturbed);
      INFO(shape << (perturbed ? ", perturbed normals" : ", true normals"));
      const int F = s.mesh.num_faces();
      REQUIRE(F > 500);
      const Eigen::MatrixX3d& U = s.normals.vertex;
      const double* x[3] = {s.mesh.positions.col(0).data(), s.mesh.positions.col(1).data(),
                            s.mesh.positions.col(2).data()};
      const double* u[3] = {U.col(0).data(), U.col(1).data(), U.col(2).data()};
      for (const double kappa : {2.0, 1.0})
        for (const auto isa : isas) {
          INFO("kappa " << kappa << ", isa " << int(isa));
          std::vector<double> t(std::size_t(F) * detail::kTermsStride), p(std::size_t(F) * 16);
          REQUIRE(detail::interpolated_face_range(s.mesh.faces.data(), 0, F, x, u, kappa, t.data(), p.data(), isa) ==
                  -1);
          int mismatches = 0;
          for (int f = 0; f < F; ++f) {
            const InterpolatedLocal ref =
                interpolated_local(quad_corners(s.mesh, f), quad_corner_rows(s.mesh, U, f), 0.1, kappa);
            Eigen::Matrix4d M, K1, PD;
            unpack(t.data() + std::size_t(f) * detail::kTermsStride, p.data() + std::size_t(f) * 16, M, K1, PD);
            if (!same_bits(M, ref.mass) || !same_bits(K1, ref.sharp_stiffness) ||
                !same_bits(PD, ref.projected_difference))
              ++mismatches;
          }
          CHECK(mismatches == 0);
        }
      // Local assembly (docs/math.md §3.6b) from the readable L_f == the method's L, bit for bit.
      const detail::VertexCorners vc = detail::vertex_corners(s.mesh);
      Eigen::SparseMatrix<double> L, M;
      detail::gather_quad_rows<2>(s.mesh, vc,
                                  [&](int f, int i, double* rows) {
                                    const InterpolatedLocal ref = interpolated_local(
                                        quad_corners(s.mesh, f), quad_corner_rows(s.mesh, U, f), 0.1, 2.0);
                                    for (int j = 0; j < 4; ++j)
                                      rows[j] = ref.mass(i, j), rows[4 + j] = ref.laplacian(i, j);
                                  },
                                  {&M, &L});
      // orientation=warn: the normals exactly as given, like the readable terms (the perturbed ones
      // have corners with u.n <= 0, which the default policy would clamp).
      const Operators ops = make_interpolated_corrected()->assemble(
          s.mesh, s.normals, Config::from_key_values({"assembly=local", "orientation=warn"}));
      CHECK(std::memcmp(ops.L.valuePtr(), L.valuePtr(), sizeof(double) * std::size_t(L.nonZeros())) == 0);
      CHECK(std::memcmp(ops.M.valuePtr(), M.valuePtr(), sizeof(double) * std::size_t(M.nonZeros())) == 0);
      CHECK(ops.L.nonZeros() == L.nonZeros());
    }
}

TEST_CASE("interpolated assembly kernel rejects a non-square quad") {
  QuadCorners x, u;
  x << 0, 0, 0, 1, 0, 0, 1, 1.01, 0, 0, 1, 0;  // x2 off the square by 1%
  for (int k = 0; k < 4; ++k) u.row(k) << 0, 0, 1;
  double terms[detail::kTermsStride], pd[16];
  CHECK_FALSE(face_terms(x, u, 2.0, terms, pd));
  x(2, 1) = 1.0;
  CHECK(face_terms(x, u, 2.0, terms, pd));
}

TEST_CASE("vectorized face kernel (SSE2, AVX2) gives the scalar kernel's bits and finds non-squares") {
  // 103 random squares, each with its own 4 vertices: an odd count leaves a tail for the scalar
  // loop after the vector batches.
  std::mt19937 rng(5);
  const int F = 103;
  std::vector<int> faces(4 * F);
  std::vector<double> pos[3], nrm[3];
  for (int c = 0; c < 3; ++c) pos[c].resize(4 * F), nrm[c].resize(4 * F);
  for (int f = 0; f < F; ++f) {
    const KernelCase kc = random_case(rng, f % 2 == 0);
    for (int k = 0; k < 4; ++k) {
      faces[std::size_t(4 * f + k)] = 4 * f + k;
      for (int c = 0; c < 3; ++c)
        pos[c][std::size_t(4 * f + k)] = kc.x(k, c), nrm[c][std::size_t(4 * f + k)] = kc.u(k, c);
    }
  }
  const double* x[3] = {pos[0].data(), pos[1].data(), pos[2].data()};
  const double* u[3] = {nrm[0].data(), nrm[1].data(), nrm[2].data()};
  auto run = [&](detail::FaceKernelIsa isa, std::vector<double>& t, std::vector<double>& p) {
    t.assign(std::size_t(F) * detail::kTermsStride, 0.0);
    p.assign(std::size_t(F) * 16, 0.0);
    return detail::interpolated_face_range(faces.data(), 0, F, x, u, 2.0, t.data(), p.data(), isa);
  };
  std::vector<double> t0, p0;
  REQUIRE(run(detail::FaceKernelIsa::Scalar, t0, p0) == -1);
  for (const auto isa : test::face_kernel_isas()) {  // Scalar against itself too: the reference run is repeatable
    INFO("isa " << int(isa));
    std::vector<double> t, p;
    REQUIRE(run(isa, t, p) == -1);
    // exact (memcmp also tells -0.0 from +0.0): the same IEEE operations in the same order
    CHECK(std::memcmp(t.data(), t0.data(), t.size() * sizeof(double)) == 0);
    CHECK(std::memcmp(p.data(), p0.data(), p.size() * sizeof(double)) == 0);
    // a range that does not start on a batch boundary (TBB ranges are arbitrary)
    std::vector<double> t3(t0.size(), 0.0), p3(p0.size(), 0.0);
    REQUIRE(detail::interpolated_face_range(faces.data(), 3, F, x, u, 2.0, t3.data(), p3.data(), isa) == -1);
    CHECK(std::memcmp(t3.data() + 3 * detail::kTermsStride, t0.data() + 3 * detail::kTermsStride,
                      (t.size() - 3 * detail::kTermsStride) * sizeof(double)) == 0);
    CHECK(std::memcmp(p3.data() + 3 * 16, p0.data() + 3 * 16, (p.size() - 3 * 16) * sizeof(double)) == 0);
  }
  // Non-square faces: the first of the range is reported by every ISA, whether it sits inside a
  // vector batch (42, 43 in one batch of 2 and of 4 lanes) or in the scalar tail (102).
  pos[1][std::size_t(4 * 102 + 2)] += 1e-3;
  const std::vector<detail::FaceKernelIsa> isas = test::face_kernel_isas();
  for (const auto isa : isas) {
    std::vector<double> t, p;
    CHECK(run(isa, t, p) == 102);
  }
  pos[1][std::size_t(4 * 43 + 2)] += 1e-3;
  pos[1][std::size_t(4 * 42 + 2)] += 1e-3;
  for (const auto isa : isas) {
    std::vector<double> t, p;
    CHECK(run(isa, t, p) == 42);
  }
}
