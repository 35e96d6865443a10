// The vectorized per-face kernel of the corrected FEM (fem_kernel.hpp) gives the scalar kernel's
// bits for every instruction set, and the scalar kernel matches the readable local operators of
// spec §4.3-§4.4.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <corrlap/discretizations/corrected_fem.hpp>
#include <corrlap/discretizations/detail/fem_kernel.hpp>

using namespace corrlap;

TEST_CASE("fem face kernel: SSE2 and AVX2 lanes give the scalar bits; values match spec §4.3-§4.4") {
  // 37 random planar quads (odd: the last faces go through the scalar tail), each with its own
  // vertices, and unit face normals tilted from the quad's normal.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const int F = 37;
  Eigen::MatrixX3d P(4 * F, 3), U(F, 3);
  std::vector<int> faces(4 * F);
  for (int f = 0; f < F; ++f) {
    const Eigen::Vector3d o(uni(rng), uni(rng), uni(rng));
    const Eigen::Vector3d a = Eigen::Vector3d(uni(rng), uni(rng), uni(rng)).normalized() * (0.01 + std::abs(uni(rng)));
    Eigen::Vector3d b = Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
    b = (b - b.dot(a) / a.squaredNorm() * a).normalized() * (0.01 + std::abs(uni(rng)));
    const Eigen::Vector3d x[4] = {o, o + a, o + a + b, o + b};
    for (int k = 0; k < 4; ++k) {
      P.row(4 * f + k) = x[k].transpose();
      faces[std::size_t(4 * f + k)] = 4 * f + k;
    }
    const Eigen::Vector3d n = a.cross(b).normalized();
    U.row(f) = (n + 0.4 * Eigen::Vector3d(uni(rng), uni(rng), uni(rng))).normalized().transpose();
  }
  // Face 9 (inside a vector batch) has a zero-length first edge: the scalar code skips the
  // normalization there (n2 > 0 fails) and the vector code divides by 1.0. Its zero area makes
  // most values NaN; which NaN payload survives depends on operand order, which compilers may
  // commute, so that face is compared value by value (NaN where the scalar has NaN).
  const int degenerate = 9;
  P.row(4 * degenerate + 1) = P.row(4 * degenerate);
  // Bitwise equal except on the degenerate face, where NaN matches NaN (any payload).
  auto same = [&](const std::vector<double>& a, const std::vector<double>& b, int first) {
    const std::size_t G = detail::kFemFaceValues;
    for (std::size_t i = std::size_t(first) * G; i < a.size(); ++i) {
      if (i / G == std::size_t(degenerate) && std::isnan(a[i]) && std::isnan(b[i])) continue;
      if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) return false;
    }
    return true;
  };
  auto run = [&](detail::FaceKernelIsa isa) {
    std::vector<double> g(std::size_t(F) * detail::kFemFaceValues, -7.0);
    detail::fem_face_range(P.data(), std::size_t(P.rows()), faces.data(), U.data(), std::size_t(F), 0, F, g.data(), isa);
    return g;
  };
  const std::vector<double> g0 = run(detail::FaceKernelIsa::Scalar);
  std::vector<detail::FaceKernelIsa> isas = {detail::FaceKernelIsa::Sse2, detail::FaceKernelIsa::Best};
  if (detail::cpu_has_avx2()) isas.push_back(detail::FaceKernelIsa::Avx2);
  for (const auto isa : isas) {
    INFO("isa " << int(isa));
    const std::vector<double> g = run(isa);
    CHECK(same(g, g0, 0));
    // a range that does not start on a batch boundary (TBB ranges are arbitrary)
    std::vector<double> g3(g.size(), -7.0);
    detail::fem_face_range(P.data(), std::size_t(P.rows()), faces.data(), U.data(), std::size_t(F), 3, F, g3.data(), isa);
    CHECK(same(g3, g0, 3));
  }
  // The scalar values are the entries of the local stiffness and mass (spec §4.3, §4.4).
  for (int f = 0; f < F; ++f) {
    if (f == degenerate) continue;
    QuadCorners x;
    for (int k = 0; k < 4; ++k) x.row(k) = P.row(4 * f + k);
    const FemLocalFrame fr = corrected_fem_local_frame(x, U.row(f).transpose());
    const Eigen::Matrix4d K = corrected_fem_local_stiffness(fr.u_local);
    const Eigen::Matrix4d M = corrected_fem_local_mass(fr.area, fr.u_local.z());
    const double* g = g0.data() + std::size_t(f) * detail::kFemFaceValues;
    const double scale = K.cwiseAbs().maxCoeff();
    CHECK(std::abs(g[0] - K(0, 0)) <= 1e-12 * scale);  // self
    CHECK(std::abs(g[1] - K(0, 1)) <= 1e-12 * scale);  // o1
    CHECK(std::abs(g[2] - K(0, 3)) <= 1e-12 * scale);  // o2
    CHECK(std::abs(g[3] - K(0, 2)) <= 1e-12 * scale);  // o
    CHECK(std::abs(g[4] - K(1, 1)) <= 1e-12 * scale);  // self - 2 eta
    CHECK(std::abs(g[5] - K(1, 3)) <= 1e-12 * scale);  // o + 2 eta
    CHECK(std::abs(g[6] - M(0, 2)) <= 1e-13 * M(0, 0));  // area z / 36
    CHECK(std::abs(g[7] - M.row(0).sum()) <= 1e-13 * M.row(0).sum());  // area z / 4 = row sum
  }
}
