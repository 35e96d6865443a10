// Local matrices of the quad discretizations without a mesh (docs/math.md §12.2).
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/corrected_fem.hpp>
#include <corrlap/discretizations/interpolated_corrected.hpp>
#include <corrlap/discretizations/polydec.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <random>

#include "reference_support.hpp"

using namespace corrlap;
using Eigen::Matrix4d;
using Eigen::Vector3d;

namespace {

// Unit square surfel of side h in the plane z = 0, outward +z (docs/math.md §0 corner order).
QuadCorners flat_surfel(double h) {
  QuadCorners x;
  x << 0, 0, 0, h, 0, 0, h, h, 0, 0, h, 0;
  return x;
}

QuadCorners constant_rows(const Vector3d& u) {
  QuadCorners r;
  for (int k = 0; k < 4; ++k) r.row(k) = u.transpose();
  return r;
}

Matrix4d bilinear_stiffness() {
  Matrix4d K;
  K << 4, -1, -2, -1, -1, 4, -1, -2, -2, -1, 4, -1, -1, -2, -1, 4;
  return K / 6.0;
}

// -(K0 + lambda w w^T) of docs/math.md §2.4.
Matrix4d polydec_closed_form(double lambda) {
  Matrix4d K0;
  K0 << 1, 0, -1, 0, 0, 1, 0, -1, -1, 0, 1, 0, 0, -1, 0, 1;
  Eigen::Vector4d w(1, -1, 1, -1);
  return -(0.5 * K0 + lambda * w * w.transpose());
}

// Single-surfel regression case of docs/math.md §12.2 (h = 0.5, outward +x).
QuadCorners regression_corners() {
  const double h = 0.5;
  QuadCorners x;
  x << 0, 0, 0, 0, h, 0, 0, h, h, 0, 0, h;
  return x;
}
QuadCorners regression_vertex_normals() {
  QuadCorners u;
  u.row(0) = Vector3d(1, 0.2, -0.1).normalized().transpose();
  u.row(1) = Vector3d(0.9, -0.3, 0.2).normalized().transpose();
  u.row(2) = Vector3d(1, 0.1, 0.3).normalized().transpose();
  u.row(3) = Vector3d(0.8, 0.4, 0.1).normalized().transpose();
  return u;
}
const Vector3d regression_face_normal = Vector3d(0.9, 0.3, -0.2).normalized();

// The reference values are printed with 9 significant digits: they are exact to half a unit of
// the 9th digit (exact zeros to round-off).
void check_9_digits(double got, double expected) {
  const double unit = expected == 0.0 ? 0.0 : std::pow(10.0, std::floor(std::log10(std::abs(expected))) - 8);
  CHECK(std::abs(got - expected) <= 0.5 * unit + 1e-13);
}
template <class Row>
void check_row(const Row& got, std::initializer_list<double> expected) {
  int i = 0;
  for (double e : expected) check_9_digits(got(i++), e);
}

void check_local_laplacian_properties(const Matrix4d& L) {
  const double scale = L.cwiseAbs().maxCoeff();
  CHECK((L * Eigen::Vector4d::Ones()).cwiseAbs().maxCoeff() <= 1e-14 * scale);
  CHECK((L - L.transpose()).cwiseAbs().maxCoeff() <= 1e-14 * scale);
  Eigen::SelfAdjointEigenSolver<Matrix4d> es(L);
  CHECK(es.eigenvalues().maxCoeff() <= 1e-14 * scale);
}

}  // namespace

TEST_CASE("fem local stiffness with u = n is the bilinear stiffness and does not depend on h") {
  for (double h : {1.0, 0.1, 0.013}) {
    const FemLocalFrame fr = corrected_fem_local_frame(flat_surfel(h), Vector3d(0, 0, 1));
    CHECK((fr.u_local - Vector3d(0, 0, 1)).norm() <= 1e-15);
    CHECK(std::abs(fr.area - h * h) <= 1e-15 * h * h);
    CHECK((corrected_fem_local_stiffness(fr.u_local) - bilinear_stiffness()).cwiseAbs().maxCoeff() <= 1e-15);
  }
}

TEST_CASE("fem local mass sums to h^2 z, lumped and full agree in total") {
  const Vector3d u = Vector3d(0.3, -0.2, 0.9).normalized();
  const FemLocalFrame fr = corrected_fem_local_frame(flat_surfel(0.2), u);
  CHECK(fr.u_local.z() == doctest::Approx(u.z()).epsilon(1e-15));
  CHECK(corrected_fem_local_mass(fr.area, fr.u_local.z()).sum() == doctest::Approx(0.04 * u.z()).epsilon(1e-14));
  CHECK(corrected_fem_local_lumped_mass(fr.area, fr.u_local.z()).sum() == doctest::Approx(0.04 * u.z()).epsilon(1e-14));
  // Same u, another h: stiffness identical (docs/math.md §4.3: scale invariant).
  const FemLocalFrame fr2 = corrected_fem_local_frame(flat_surfel(3.0), u);
  CHECK(
      (corrected_fem_local_stiffness(fr.u_local) - corrected_fem_local_stiffness(fr2.u_local)).cwiseAbs().maxCoeff() <=
      1e-15);
}

TEST_CASE("fem local stiffness equals the paper's Fig. 2 matrix written out in docs/math.md §4.3 for unit u") {
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 20; ++trial) {
    Vector3d u(g(rng), g(rng), std::abs(g(rng)) + 0.2);
    u.normalize();
    const double x = u.x(), y = u.y(), z = u.z();
    Matrix4d K;
    K << 3 * x * y + 2 + 2 * z * z, 2 * y * y - 1 - x * x, -3 * x * y - 1 - z * z, 2 * x * x - 1 - y * y,  //
        2 * y * y - 1 - x * x, -3 * x * y + 2 + 2 * z * z, 2 * x * x - 1 - y * y, 3 * x * y - 1 - z * z,   //
        -3 * x * y - 1 - z * z, 2 * x * x - 1 - y * y, 3 * x * y + 2 + 2 * z * z, 2 * y * y - 1 - x * x,   //
        2 * x * x - 1 - y * y, 3 * x * y - 1 - z * z, 2 * y * y - 1 - x * x, -3 * x * y + 2 + 2 * z * z;
    K /= 6 * z;
    const Matrix4d Kf = corrected_fem_local_stiffness(u);
    CHECK((Kf - K).cwiseAbs().maxCoeff() <= 1e-13 * K.cwiseAbs().maxCoeff());
    check_local_laplacian_properties(-Kf);
  }
}

TEST_CASE("polydec local laplacian on a flat surfel is -(K0 + lambda w w^T) for any h") {
  for (double lambda : {1.0, 0.1, 1.0 / 6.0})
    for (double h : {1.0, 0.2}) {
      const PolyDecLocal loc = polydec_local(flat_surfel(h), lambda);
      CHECK(loc.area == doctest::Approx(h * h).epsilon(1e-14));
      CHECK((loc.laplacian - polydec_closed_form(lambda)).cwiseAbs().maxCoeff() <= 1e-14);
    }
  Matrix4d expected;
  expected << -1.5, 1, -0.5, 1, 1, -1.5, 1, -0.5, -0.5, 1, -1.5, 1, 1, -0.5, 1, -1.5;
  CHECK((polydec_local(flat_surfel(0.3), 1.0).laplacian - expected).cwiseAbs().maxCoeff() <= 1e-14);
}

TEST_CASE("polydec and interpolated equal minus the FEM stiffness on a flat surfel iff lambda = 1/6") {
  const Matrix4d Kfem = bilinear_stiffness();
  const QuadCorners n = constant_rows(Vector3d(0, 0, 1));
  CHECK((polydec_local(flat_surfel(0.5), 1.0 / 6.0).laplacian + Kfem).cwiseAbs().maxCoeff() <= 1e-14);
  CHECK((interpolated_local(flat_surfel(0.5), n, 1.0 / 6.0).laplacian + Kfem).cwiseAbs().maxCoeff() <= 1e-14);
  CHECK((interpolated_local(flat_surfel(0.5), n, 0.1).laplacian + Kfem).cwiseAbs().maxCoeff() > 1e-3);
  // lambda = 0.1: rows (-0.6, 0.1, 0.4, 0.1) cyclic (docs/math.md §12.2).
  const Matrix4d L = interpolated_local(flat_surfel(0.5), n, 0.1).laplacian;
  for (int r = 0; r < 4; ++r) {
    CHECK(L(r, r) == doctest::Approx(-0.6).epsilon(1e-14));
    CHECK(L(r, (r + 1) % 4) == doctest::Approx(0.1).epsilon(1e-14));
    CHECK(L(r, (r + 2) % 4) == doctest::Approx(0.4).epsilon(1e-14));
    CHECK(L(r, (r + 3) % 4) == doctest::Approx(0.1).epsilon(1e-14));
  }
}

TEST_CASE("projected polydec: |a_f| = h^2 u.n and n_f = u on a surfel") {
  const Vector3d u = Vector3d(0.2, -0.4, 0.8).normalized();
  const PolyDecLocal loc = polydec_local(polydec_project_corners(flat_surfel(0.25), u), 1.0);
  CHECK(loc.area == doctest::Approx(0.0625 * u.z()).epsilon(1e-14));
  CHECK((loc.normal - u).norm() <= 1e-14);
  check_local_laplacian_properties(loc.laplacian);
}

TEST_CASE("interpolated: constant-u identities of docs/math.md §12.2 for kappa = 1 and 2") {
  const Vector3d n(0, 0, 1);
  const Vector3d u = Vector3d(0.3, -0.25, 0.9).normalized();
  for (double kappa : {1.0, 2.0}) {
    const InterpolatedLocal loc = interpolated_local(flat_surfel(0.2), constant_rows(u), 0.1, kappa);
    CHECK(loc.mass.sum() == doctest::Approx(loc.area).epsilon(1e-14));
    CHECK(loc.area == doctest::Approx(0.04 * u.z()).epsilon(1e-14));
    const Eigen::Matrix3d UV = loc.sharp * loc.flat;
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d expected = kappa == 1.0
                                         ? Eigen::Matrix3d(I - u * u.transpose())
                                         : Eigen::Matrix3d(I - 2.0 * u * u.transpose() + n * u.transpose() / u.z());
    CHECK((UV - expected).cwiseAbs().maxCoeff() <= 1e-13);
    // Identity on vectors orthogonal to u.
    const Vector3d g = u.cross(Vector3d(1, 2, 3)).normalized();
    CHECK((UV * g - g).norm() <= 1e-13);
    CHECK((loc.sharp * loc.projection).cwiseAbs().maxCoeff() <= 1e-12);
    CHECK((loc.projection * loc.projection - loc.projection).cwiseAbs().maxCoeff() <= 1e-12);
    // Linear precision: phi_k = g . x_k, g ⟂ u: U D phi = g and P D phi = 0.
    const QuadCorners x = flat_surfel(0.2);
    const Eigen::Vector4d phi = x * g;
    CHECK((loc.sharp * quad_difference() * phi - g).norm() <= 1e-13);
    CHECK((loc.projection * quad_difference() * phi).norm() <= 1e-13);
    check_local_laplacian_properties(loc.laplacian);
  }
}

TEST_CASE("interpolated local mass with u = n is the bilinear mass h^2/36 [4 2 1 2]") {
  const Matrix4d M = interpolated_local_mass(0.3, Eigen::Vector4d::Ones());
  Matrix4d B;
  B << 4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4;
  CHECK((M - 0.09 / 36.0 * B).cwiseAbs().maxCoeff() <= 1e-16);
}

TEST_CASE("local laplacians of every quad method are symmetric, annihilate constants and are NSD for random normals") {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  auto random_normal = [&] {
    Vector3d v(0.4 * g(rng), 0.4 * g(rng), 1.0);
    return Vector3d(v.normalized());
  };
  for (int trial = 0; trial < 30; ++trial) {
    QuadCorners u;
    for (int k = 0; k < 4; ++k) u.row(k) = random_normal().transpose();
    check_local_laplacian_properties(interpolated_local(flat_surfel(0.1), u, 0.1).laplacian);
    check_local_laplacian_properties(interpolated_local(flat_surfel(0.1), u, 1.0, 1.0).laplacian);
    check_local_laplacian_properties(
        polydec_local(polydec_project_corners(flat_surfel(0.1), random_normal()), 1.0).laplacian);
    check_local_laplacian_properties(-corrected_fem_local_stiffness(random_normal()));
  }
}

TEST_CASE("single-surfel regression values of the reference (docs/math.md §12.2, 9 digits)") {
  const QuadCorners x = regression_corners();
  const QuadCorners u = regression_vertex_normals();
  const InterpolatedLocal cc = interpolated_local(x, u, 0.1, 2.0);
  check_row(cc.mass.row(0), {0.0263681724, 0.0131161268, 0.00650439353, 0.0129793552});
  check_row(cc.mass.diagonal(), {0.0263681724, 0.026096335, 0.0260565406, 0.0255492485});
  check_9_digits(cc.mass.sum(), 0.234158167);
  check_row(cc.sharp.row(0), {-0.0553931111, -0.177616261, 0.171774037, 0.0924170971});
  check_row(cc.sharp.row(1), {1.00550089, 0, -0.994499114, 0});
  check_row(cc.sharp.row(2), {0, 1.00150831, 0, -0.998491694});
  check_row(cc.flat.row(0), {0.0523838987, 0.475517975, 0.0158825546});
  check_row(cc.flat.row(1), {-0.231773568, 0.0236589383, 0.438874444});
  check_row(cc.flat.row(2), {0.246742503, -0.417000704, 0.0485055434});
  check_row(cc.flat.row(3), {0.00479022367, 0.00649725429, -0.496324615});
  check_row(cc.laplacian.row(0), {-0.5689584, 0.096796945, 0.386175001, 0.0859864545});
  check_row(cc.laplacian.diagonal(), {-0.5689584, -0.578825515, -0.592193738, -0.554323721});

  const FemLocalFrame fr = corrected_fem_local_frame(x, regression_face_normal);
  const Matrix4d Lfem = -corrected_fem_local_stiffness(fr.u_local);
  check_row(Lfem.row(0), {-0.634133063, 0.181453738, 0.299876177, 0.152803148});
  check_row(Lfem.row(1), {0.181453738, -0.702894479, 0.152803148, 0.368637594});
  // Rows 2 and 3 repeat rows 0 and 1 with the §4.3 pattern.
  check_row(Lfem.row(2), {0.299876177, 0.152803148, -0.634133063, 0.181453738});
  check_row(Lfem.row(3), {0.152803148, 0.368637594, 0.181453738, -0.702894479});
}

TEST_CASE("cyclic relabelling and reversal with negated normals give the same assembled matrices") {
  const QuadCorners x = regression_corners();
  const QuadCorners u = regression_vertex_normals();
  SurfelMesh base;
  base.positions = x;
  base.faces.resize(1, 4);
  base.faces << 0, 1, 2, 3;
  NormalFields nf;
  nf.vertex = u;
  nf.face = regression_face_normal.transpose();
  std::vector<std::pair<std::string, Config>> methods = {
      {"fem", Config{}}, {"interpolated", Config{}}, {"projected-polydec", Config{}}, {"polydec", Config{}}};
  Config local;
  local.set("assembly", std::string("local"));
  methods.push_back({"interpolated", local});
  for (const auto& [method, params] : methods) {
    const auto disc = make_discretization(method);
    const Operators ref = disc->assemble(base, nf, params);
    for (int shift = 0; shift < 4; ++shift)
      for (bool reverse : {false, true}) {
        SurfelMesh m = base;
        NormalFields n2 = nf;
        for (int k = 0; k < 4; ++k) m.faces(0, k) = reverse ? (shift - k + 8) % 4 : (shift + k) % 4;
        if (reverse) {
          n2.vertex = -n2.vertex;
          n2.face = -n2.face;
        }
        const Operators o = disc->assemble(m, n2, params);
        const auto method_copy = method;  // clang 14: no structured binding inside CAPTURE/INFO
        INFO(method_copy << " shift " << shift << " reverse " << reverse);
        CHECK(test::relative_difference(o.L, ref.L) <= 1e-13);
        CHECK(test::relative_difference(o.M, ref.M) <= 1e-13);
      }
  }
}
