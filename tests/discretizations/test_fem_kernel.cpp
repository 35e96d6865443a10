// The fast per-face kernel of the corrected FEM (corrected_fem_fast.cpp) gives the bits of the
// readable local operators of docs/math.md §4.2-§4.4 (corrected_fem.cpp) for every instruction set, face by
// face and assembled.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/assembly/detail/quad_row_gather.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/discretizations/corrected_fem.hpp>
#include <corrlap/discretizations/detail/fem_kernel.hpp>
#include <cstring>
#include <random>
#include <vector>

#include "reference_support.hpp"

using namespace corrlap;

TEST_CASE("fem face kernel on random quads: every ISA gives the scalar bits, which are the readable values") {
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
    detail::fem_face_range(P.data(), std::size_t(P.rows()), faces.data(), U.data(), std::size_t(F), 0, F, g.data(),
                           isa);
    return g;
  };
  const std::vector<double> g0 = run(detail::FaceKernelIsa::Scalar);
  for (const auto isa : test::face_kernel_isas()) {  // Scalar against itself too: the reference run is repeatable
    INFO("isa " << int(isa));
    const std::vector<double> g = run(isa);
    CHECK(same(g, g0, 0));
    // a range that does not start on a batch boundary (TBB ranges are arbitrary)
    std::vector<double> g3(g.size(), -7.0);
    detail::fem_face_range(P.data(), std::size_t(P.rows()), faces.data(), U.data(), std::size_t(F), 3, F, g3.data(),
                           isa);
    CHECK(same(g3, g0, 3));
  }
  // The scalar values are the entries of the local stiffness and mass (docs/math.md §4.3, §4.4).
  for (int f = 0; f < F; ++f) {
    if (f == degenerate) continue;
    QuadCorners x;
    for (int k = 0; k < 4; ++k) x.row(k) = P.row(4 * f + k);
    const FemLocalFrame fr = corrected_fem_local_frame(x, U.row(f).transpose());
    const Eigen::Matrix4d K = corrected_fem_local_stiffness(fr.u_local);
    const Eigen::Matrix4d M = corrected_fem_local_mass(fr.area, fr.u_local.z());
    const double* g = g0.data() + std::size_t(f) * detail::kFemFaceValues;
    // Bit for bit (the readable form uses the fast kernel's operation order).
    CHECK(g[0] == K(0, 0));                                                         // self
    CHECK(g[1] == K(0, 1));                                                         // o1
    CHECK(g[2] == K(0, 3));                                                         // o2
    CHECK(g[3] == K(0, 2));                                                         // o
    CHECK(g[4] == K(1, 1));                                                         // self - 2 eta
    CHECK(g[5] == K(1, 3));                                                         // o + 2 eta
    CHECK(g[6] == M(0, 2));                                                         // area z / 36
    CHECK(g[7] == corrected_fem_local_lumped_mass(fr.area, fr.u_local.z())(0, 0));  // area z / 4
  }
}

namespace {
bool same_bits(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a.nonZeros() == b.nonZeros() &&
         std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(), sizeof(int) * std::size_t(a.cols() + 1)) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * std::size_t(a.nonZeros())) == 0 &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * std::size_t(a.nonZeros())) == 0;
}
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
}  // namespace

TEST_CASE("fem fast face values and assembly are bitwise the readable local matrices") {
  const std::vector<detail::FaceKernelIsa> isas = test::face_kernel_isas();
  for (const char* shape : {"sphere1", "torus"})
    for (bool perturbed : {false, true}) {
      const test::SphereCase s = test::shape_case(shape, shape == std::string("torus") ? 0.5 : 0.125, perturbed);
      INFO(shape << (perturbed ? ", perturbed normals" : ", true normals"));
      const int F = s.mesh.num_faces();
      REQUIRE(F > 500);
      const Eigen::MatrixX3d& U = s.normals.face;
      // Readable local matrices of every face (docs/math.md §4.2-§4.4).
      std::vector<Eigen::Matrix4d> K(std::size_t(F), Eigen::Matrix4d::Zero()), M(K), ML(K);
      for (int f = 0; f < F; ++f) {
        const FemLocalFrame fr = corrected_fem_local_frame(quad_corners(s.mesh, f), U.row(f).transpose());
        K[std::size_t(f)] = corrected_fem_local_stiffness(fr.u_local);
        M[std::size_t(f)] = corrected_fem_local_mass(fr.area, fr.u_local.z());
        ML[std::size_t(f)] = corrected_fem_local_lumped_mass(fr.area, fr.u_local.z());
      }
      // Fast face values for every ISA: the distinct entries, bit for bit.
      for (const auto isa : isas) {
        INFO("isa " << int(isa));
        std::vector<double> g(std::size_t(F) * detail::kFemFaceValues);
        detail::fem_face_range(s.mesh.positions.data(), std::size_t(s.mesh.num_vertices()), s.mesh.faces.data(),
                               U.data(), std::size_t(F), 0, F, g.data(), isa);
        bool all = true;
        for (int f = 0; f < F; ++f) {
          const double* gf = g.data() + std::size_t(f) * detail::kFemFaceValues;
          const Eigen::Matrix4d& k = K[std::size_t(f)];
          all = all && same_bits(gf[0], k(0, 0)) && same_bits(gf[1], k(0, 1)) && same_bits(gf[2], k(0, 3)) &&
                same_bits(gf[3], k(0, 2)) && same_bits(gf[4], k(1, 1)) && same_bits(gf[5], k(1, 3)) &&
                same_bits(gf[6], M[std::size_t(f)](0, 2)) && same_bits(gf[7], ML[std::size_t(f)](0, 0));
        }
        CHECK(all);
      }
      // Assembled from the readable matrices by the direct gather (incident faces ascending, the
      // documented summation order) == the method's L and M, with and without a pattern.
      const detail::VertexCorners vc = detail::vertex_corners(s.mesh);
      Eigen::SparseMatrix<double> L, Mf;
      detail::gather_quad_rows<2>(s.mesh, vc,
                                  [&](int f, int i, double* rows) {
                                    for (int j = 0; j < 4; ++j)
                                      rows[j] = -K[std::size_t(f)](i, j), rows[4 + j] = M[std::size_t(f)](i, j);
                                  },
                                  {&L, &Mf});
      // orientation=warn: the normals exactly as given, like the readable matrices (some perturbed
      // ones have u.n <= 0, which the default policy would clamp).
      const auto fem = make_corrected_fem();
      const QuadPattern pattern = QuadPattern::build(s.mesh);
      const Config as_given = Config::from_key_values({"orientation=warn"});
      for (const Operators& ops :
           {fem->assemble(s.mesh, s.normals, as_given), fem->assemble(s.mesh, s.normals, as_given, pattern)}) {
        CHECK(same_bits(ops.L, L));
        CHECK(same_bits(ops.M, Mf));
      }
      const Operators lumped =
          fem->assemble(s.mesh, s.normals, Config::from_key_values({"mass=lumped", "orientation=warn"}), pattern);
      bool diag = lumped.M.nonZeros() == s.mesh.num_vertices();
      for (int v = 0; diag && v < s.mesh.num_vertices(); ++v) {
        double d = 0.0;  // corners at v, ascending face order
        for (int a = vc.start[std::size_t(v)]; a < vc.start[std::size_t(v) + 1]; ++a) {
          const int c = vc.corner[std::size_t(a)];
          d += ML[std::size_t(c >> 2)](c & 3, c & 3);
        }
        diag = same_bits(lumped.M.valuePtr()[v], d);
      }
      CHECK(diag);
    }
}
