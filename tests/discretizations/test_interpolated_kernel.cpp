// The assembly kernel of the interpolated corrected calculus (interpolated_kernel.hpp, scalar
// closed forms) computes the same M_{0,f}, D^T (S^T S / ubar^z) D and P_f D as the readable
// reference interpolated_local() (spec §3.2-§3.5), for squares of any orientation and size.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cstring>
#include <random>
#include <vector>

#include <corrlap/discretizations/interpolated_corrected.hpp>
#include <corrlap/discretizations/detail/interpolated_kernel.hpp>

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
  if (!axis_aligned) R = Eigen::Quaterniond(Eigen::Vector4d(g(rng), g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
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

}  // namespace

TEST_CASE("interpolated assembly kernel equals interpolated_local (M0, K1, P D) to round-off") {
  std::mt19937 rng(11);
  const Eigen::Matrix4d& D = quad_difference();
  for (int trial = 0; trial < 400; ++trial) {
    const bool axis = trial % 2 == 0;
    const KernelCase c = random_case(rng, axis);
    const double kappa = trial % 3 == 0 ? 1.0 : 2.0;
    const InterpolatedLocal ref = interpolated_local(c.x, c.u, 0.1, kappa);
    const double* xp[4] = {&c.x(0, 0), &c.x(1, 0), &c.x(2, 0), &c.x(3, 0)};  // row-major rows
    const double* up[4] = {&c.u(0, 0), &c.u(1, 0), &c.u(2, 0), &c.u(3, 0)};
    double terms[detail::kTermsStride], pd[16];
    REQUIRE(detail::interpolated_face_terms(xp, up, kappa, terms, pd));
    Eigen::Matrix4d M, K1, PD;
    for (int i = 0; i < 4; ++i) {
      double row[4];
      detail::interpolated_mass_row(terms, i, row);
      for (int j = 0; j < 4; ++j) {
        M(i, j) = row[j];
        K1(i, j) = terms[detail::kTermsK1 + detail::kSym[i][j]];
        PD(i, j) = pd[4 * i + j];
      }
    }
    const Eigen::Matrix4d K1_ref = D.transpose() * (ref.S.transpose() * ref.S / ref.ubar_z) * D;
    const Eigen::Matrix4d PD_ref = ref.projection * D;
    INFO("trial " << trial << (axis ? " (axis-aligned)" : " (rotated)"));
    CHECK(max_abs(M - ref.mass) <= 1e-14 * max_abs(ref.mass));
    CHECK(max_abs(K1 - K1_ref) <= 1e-13 * max_abs(K1_ref));
    CHECK(max_abs(PD - PD_ref) <= 1e-13 * max_abs(PD_ref));
    // And the local Laplacian of spec §3.5: L_f = -(K1 + lambda (P D)^T (P D)).
    const Eigen::Matrix4d Lf = -(K1 + 0.1 * PD.transpose() * PD);
    CHECK(max_abs(Lf - ref.laplacian) <= 1e-13 * max_abs(ref.laplacian));
  }
}

TEST_CASE("interpolated assembly kernel rejects a non-square quad") {
  QuadCorners x, u;
  x << 0, 0, 0, 1, 0, 0, 1, 1.01, 0, 0, 1, 0;  // x2 off the square by 1%
  for (int k = 0; k < 4; ++k) u.row(k) << 0, 0, 1;
  const double* xp[4] = {&x(0, 0), &x(1, 0), &x(2, 0), &x(3, 0)};
  const double* up[4] = {&u(0, 0), &u(1, 0), &u(2, 0), &u(3, 0)};
  double terms[detail::kTermsStride], pd[16];
  CHECK_FALSE(detail::interpolated_face_terms(xp, up, 2.0, terms, pd));
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
      for (int c = 0; c < 3; ++c) pos[c][std::size_t(4 * f + k)] = kc.x(k, c), nrm[c][std::size_t(4 * f + k)] = kc.u(k, c);
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
  std::vector<detail::FaceKernelIsa> isas = {detail::FaceKernelIsa::Sse2, detail::FaceKernelIsa::Best};
  if (detail::cpu_has_avx2()) isas.push_back(detail::FaceKernelIsa::Avx2);
  for (const auto isa : isas) {
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
  isas.push_back(detail::FaceKernelIsa::Scalar);
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
