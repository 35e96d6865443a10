// Virtual refinement: uncorrected baseline (docs/math.md §5.1) and corrected VRM (docs/math.md §5.2, §12.2, §12.6).
#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/discretizations/virtual_refinement.hpp>
#include <random>

#include "discretizations/test_vrm_support.hpp"

using namespace corrlap;

namespace {

QuadPositions surfel_corners(double h, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  QuadPositions X;
  X << 0, 0, 0, 0, h, 0, 0, h, h, 0, 0, h;  // outward +x (docs/math.md §12.2)
  X.rowwise() += offset.transpose();
  return X;
}

Eigen::Matrix4d closed_form_K() { return Eigen::Matrix4d::Identity() - 0.25 * Eigen::Matrix4d::Ones(); }

double max_abs(const Eigen::SparseMatrix<double>& A) {
  double m = 0;
  for (int c = 0; c < A.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) m = std::max(m, std::abs(it.value()));
  return m;
}

// Random unit vector with u.n > 0 and u.n >= min_dot.
Eigen::Vector3d random_normal(std::mt19937& rng, const Eigen::Vector3d& n, double min_dot) {
  std::normal_distribution<double> g;
  for (;;) {
    Eigen::Vector3d v(g(rng), g(rng), g(rng));
    v.normalize();
    if (v.dot(n) < 0) v = -v;
    if (v.dot(n) >= min_dot) return v;
  }
}

}  // namespace

TEST_CASE("cotan triangle stiffness of an equilateral triangle is cot(60 deg)/2 off the diagonal") {
  Eigen::Matrix3d K;
  REQUIRE(cotan_triangle_stiffness(1, 1, 1, K));
  const double g = 0.5 / std::tan(M_PI / 3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) CHECK(K(i, j) == doctest::Approx(i == j ? 2 * g : -g).epsilon(1e-14));
  CHECK(heron_area(1, 1, 1) == doctest::Approx(std::sqrt(3.0) / 4).epsilon(1e-15));
  CHECK_FALSE(cotan_triangle_stiffness(1, 2, 3, K));  // flat: skipped like pmp
  CHECK(K.isZero());
  // mixed Voronoi mass sums to the area (acute and obtuse triangles)
  const Eigen::Vector3d m1 = mixed_voronoi_triangle_mass({0, 0, 0}, {1, 0, 0}, {0.3, 0.8, 0});
  const Eigen::Vector3d m2 = mixed_voronoi_triangle_mass({0, 0, 0}, {1, 0, 0}, {0.5, 0.1, 0});
  CHECK(m1.sum() == doctest::Approx(0.4).epsilon(1e-14));
  CHECK(m2.sum() == doctest::Approx(0.05).epsilon(1e-14));
  CHECK(m2[2] == doctest::Approx(0.025).epsilon(1e-14));  // obtuse corner gets half the area
}

TEST_CASE("uncorrected VRM on a surfel gives the closed form of docs/math.md §5.1 anywhere in space") {
  for (double h : {1.0, 0.5, 0.01})
    for (const Eigen::Vector3d& off : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10.5, -3.25, 7)}) {
      CAPTURE(h);
      const VrmLocal loc = vrm_local(surfel_corners(h, off));
      CHECK((loc.w - Eigen::Vector4d::Constant(0.25)).cwiseAbs().maxCoeff() < 1e-12);
      CHECK((loc.K - closed_form_K()).cwiseAbs().maxCoeff() < 1e-12);
      CHECK((loc.M - h * h / 4 * Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff() < 1e-12 * h * h);
      CHECK(loc.skipped_triangles == 0);
    }
}

TEST_CASE("uncorrected VRM virtual vertex of a non-planar quad minimizes the fan squared areas") {
  QuadPositions X;
  X << 0, 0, 0, 1, 0, 0.2, 1.1, 1, -0.1, 0, 0.9, 0.3;
  const Eigen::Vector4d w = vrm_virtual_weights(X);
  CHECK(w.sum() == doctest::Approx(1.0).epsilon(1e-13));
  auto energy = [&](const Eigen::Vector3d& p) {
    double e = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d xk = X.row(k), d = X.row((k + 1) % 4) - X.row(k);
      e += (xk - p).cross(d).squaredNorm();
    }
    return e;
  };
  const Eigen::Vector3d p = X.transpose() * w;
  const double e0 = energy(p);
  for (int a = 0; a < 3; ++a)
    for (double s : {-1e-4, 1e-4}) {
      Eigen::Vector3d q = p;
      q[a] += s;
      CHECK(energy(q) >= e0 - 1e-15);
    }
  // K_f rows sum to zero and K_f is symmetric positive semi-definite; M lumped with sum = fan area
  const VrmLocal loc = vrm_local(X);
  CHECK((loc.K * Eigen::Vector4d::Ones()).cwiseAbs().maxCoeff() < 1e-13);
  CHECK((loc.K - loc.K.transpose()).cwiseAbs().maxCoeff() < 1e-14);
  CHECK(Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(loc.K).eigenvalues().minCoeff() > -1e-13);
  CHECK((loc.M - Eigen::Matrix4d(loc.M.diagonal().asDiagonal())).isZero());
}

TEST_CASE("corrected VRM with u = n reproduces docs/math.md §5.2 checks: centre, I - 11^T/4, h^2/6 I + h^2/48 11^T") {
  for (double h : {1.0, 0.5, 0.02}) {
    CAPTURE(h);
    const QuadPositions X = surfel_corners(h, Eigen::Vector3d(3, -2, 1));
    QuadPositions U;
    U.rowwise() = Eigen::RowVector3d(1, 0, 0);
    const CorrectedVrmLocal loc = corrected_vrm_local(X, U, Eigen::Vector3d(1, 0, 0));
    CHECK(loc.point.converged);
    CHECK(loc.point.s == doctest::Approx(0.5).epsilon(1e-14));
    CHECK(loc.point.t == doctest::Approx(0.5).epsilon(1e-14));
    CHECK((loc.K - closed_form_K()).cwiseAbs().maxCoeff() < 1e-12);
    const Eigen::Matrix4d Mexp = h * h / 6 * Eigen::Matrix4d::Identity() + h * h / 48 * Eigen::Matrix4d::Ones();
    CHECK((loc.M - Mexp).cwiseAbs().maxCoeff() < 1e-14 * h * h);
    CHECK((loc.areas - Eigen::Vector4d::Constant(h * h / 4)).cwiseAbs().maxCoeff() < 1e-15);
    const CorrectedVrmLocal lumped = corrected_vrm_local(X, U, Eigen::Vector3d(1, 0, 0), true);
    CHECK((lumped.M - h * h / 4 * Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff() < 1e-14 * h * h);
  }
}

TEST_CASE("corrected fan energy: analytic gradient and Hessian agree with finite differences") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.05, 1.0), P(0.1, 0.9);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector4d uz(U(rng), U(rng), U(rng), U(rng));
    const double s = P(rng), t = P(rng), eps = 1e-6;
    Eigen::Vector2d g;
    Eigen::Matrix2d H;
    corrected_fan_energy(uz, s, t, &g, &H);
    Eigen::Vector2d gp, gm, gq, gr;
    const double fd_s =
        (corrected_fan_energy(uz, s + eps, t, &gp) - corrected_fan_energy(uz, s - eps, t, &gm)) / (2 * eps);
    const double fd_t =
        (corrected_fan_energy(uz, s, t + eps, &gq) - corrected_fan_energy(uz, s, t - eps, &gr)) / (2 * eps);
    CHECK(g[0] == doctest::Approx(fd_s).epsilon(1e-7));
    CHECK(g[1] == doctest::Approx(fd_t).epsilon(1e-7));
    const Eigen::Vector2d Hs = (gp - gm) / (2 * eps), Ht = (gq - gr) / (2 * eps);
    CHECK((H.col(0) - Hs).norm() < 1e-6 * (1 + H.norm()));
    CHECK((H.col(1) - Ht).norm() < 1e-6 * (1 + H.norm()));
    // sum of the areas is the corrected area h^2 mean(uz) for every virtual point (docs/math.md §5.2)
    CHECK(corrected_fan_areas(uz, s, t).sum() == doctest::Approx(uz.mean()).epsilon(1e-14));
  }
}

TEST_CASE("corrected VRM minimizer converges inside the surfel for random normals with u.n > 0") {
  std::mt19937 rng(2024);
  const Eigen::Vector3d n(1, 0, 0);
  const QuadPositions X = surfel_corners(0.5);
  int max_iter = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    // a mix of mild normals and nearly tangent ones (u.n down to 1e-3)
    const double min_dot = trial % 4 == 0 ? 1e-3 : 0.3;
    QuadPositions Uf;
    for (int k = 0; k < 4; ++k) Uf.row(k) = random_normal(rng, n, min_dot).transpose();
    const CorrectedVrmLocal loc = corrected_vrm_local(X, Uf, n);
    CAPTURE(trial);
    CAPTURE(Uf);
    REQUIRE(loc.point.converged);
    max_iter = std::max(max_iter, loc.point.iterations);
    CHECK(loc.point.s > 0);
    CHECK(loc.point.s < 1);
    CHECK(loc.point.t > 0);
    CHECK(loc.point.t < 1);
    const double af = 0.25 * 0.25 * (Uf * n).sum();
    CHECK(loc.areas.sum() == doctest::Approx(af).epsilon(1e-12));
    CHECK(Eigen::Vector4d::Ones().dot(loc.M * Eigen::Vector4d::Ones()) == doctest::Approx(af).epsilon(1e-12));
    CHECK((loc.K * Eigen::Vector4d::Ones()).cwiseAbs().maxCoeff() < 1e-11 * (1 + loc.K.cwiseAbs().maxCoeff()));
    CHECK((loc.K - loc.K.transpose()).cwiseAbs().maxCoeff() < 1e-12 * (1 + loc.K.cwiseAbs().maxCoeff()));
    if (trial % 500 == 0) {  // the point is the global minimum over a grid of the unit square
      double best = 1e300;
      for (int i = 1; i < 200; ++i)
        for (int j = 1; j < 200; ++j) best = std::min(best, corrected_fan_energy(Uf * n, i / 200.0, j / 200.0));
      CHECK(loc.point.energy <= best + 1e-14);
    }
  }
  MESSAGE("max Newton iterations over 20000 random surfels: " << max_iter);
  CHECK(max_iter <= 20);
}

TEST_CASE("VRM global operators on sphere1: L 1 = 0, symmetric, NSD, mass sums (docs/math.md §12.6)") {
  const SurfelMesh mesh = test::sphere1_surface(0.2);
  NormalFields nf;
  nf.vertex = test::radial(mesh.positions);
  for (const char* method : {"vrm", "corrected-vrm"}) {
    CAPTURE(method);
    const Operators ops = make_discretization(method)->assemble(mesh, nf, Config());
    CHECK(ops.warnings.empty());
    const double scale = max_abs(ops.L);
    CHECK((ops.L * Eigen::VectorXd::Ones(ops.L.cols())).cwiseAbs().maxCoeff() < 1e-13 * scale);
    CHECK((Eigen::SparseMatrix<double>(ops.L.transpose()) - ops.L).norm() < 1e-14 * ops.L.norm());
    const Eigen::MatrixXd Ld(ops.L);
    CHECK(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Ld).eigenvalues().maxCoeff() < 1e-12 * scale);
    const double total = ops.M.sum();
    if (std::string(method) == "vrm") {
      CHECK(total == doctest::Approx(mesh.num_faces() * 0.04).epsilon(1e-12));
    } else {
      double af = 0;
      for (int f = 0; f < mesh.num_faces(); ++f) {
        const Eigen::Vector3d n = mesh.surfels[std::size_t(f)].trivial_normal();
        for (int k = 0; k < 4; ++k) af += 0.04 * 0.25 * nf.vertex.row(mesh.faces(f, k)).dot(n);
      }
      CHECK(total == doctest::Approx(af).epsilon(1e-12));
      CHECK(total == doctest::Approx(4 * M_PI).epsilon(0.05));
      REQUIRE(ops.M_lumped.has_value());
      CHECK(ops.M_lumped->sum() == doctest::Approx(total).epsilon(1e-12));
      const Eigen::MatrixXd Md(ops.M);
      CHECK(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Md).eigenvalues().minCoeff() > 0);
    }
  }
}

TEST_CASE("corrected VRM is bitwise identical for 1 and 2 threads and invariant to translation") {
  const SurfelMesh mesh = test::sphere1_surface(0.25);
  NormalFields nf;
  nf.vertex = test::radial(mesh.positions);
  const auto d = make_discretization("corrected-vrm");
  set_thread_count(1);
  const Operators a = d->assemble(mesh, nf, Config());
  set_thread_count(2);
  const Operators b = d->assemble(mesh, nf, Config());
  set_thread_count(0);
  CHECK(a.L.nonZeros() == b.L.nonZeros());
  CHECK(std::equal(a.L.valuePtr(), a.L.valuePtr() + a.L.nonZeros(), b.L.valuePtr()));
  CHECK(std::equal(a.M.valuePtr(), a.M.valuePtr() + a.M.nonZeros(), b.M.valuePtr()));
  SurfelMesh moved = mesh;
  moved.positions.rowwise() += Eigen::RowVector3d(3.5, -1.25, 2);
  const Operators c = d->assemble(moved, nf, Config());
  CHECK((c.L - a.L).norm() < 1e-12 * a.L.norm());
  CHECK((c.M - a.M).norm() < 1e-12 * a.M.norm());
  // scaling by s: L unchanged, M times s^2 (docs/math.md §12.6)
  SurfelMesh scaled = mesh;
  scaled.positions *= 3.0;
  scaled.h *= 3.0;
  const Operators e = d->assemble(scaled, nf, Config());
  CHECK((e.L - a.L).norm() < 1e-12 * a.L.norm());
  CHECK((e.M - 9.0 * a.M).norm() < 1e-12 * e.M.norm());
}

TEST_CASE("corrected VRM input errors name the problem") {
  const SurfelMesh mesh = test::single_surfel(0.5);
  const auto d = make_discretization("corrected-vrm");
  NormalFields nf;
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config()), doctest::Contains("vertex"), InputError);
  nf.vertex = Eigen::MatrixX3d::Constant(3, 3, 0.0);
  nf.vertex.col(0).setOnes();
  CHECK_THROWS_AS(d->assemble(mesh, nf, Config()), InputError);  // wrong count
  nf.vertex = Eigen::MatrixX3d::Zero(4, 3);
  nf.vertex.col(0).setOnes();
  nf.vertex(2, 1) = std::nan("");
  CHECK_THROWS_AS(d->assemble(mesh, nf, Config()), InputError);  // NaN
  nf.vertex(2, 1) = 0.1;
  CHECK_THROWS_AS(d->assemble(mesh, nf, Config()), InputError);  // not unit
  CHECK_NOTHROW(d->assemble(mesh, nf, Config::from_key_values({"normalize=true"})));
  nf.vertex(2, 1) = 0.0;
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config::from_key_values({"massx=full"})), doctest::Contains("massx"),
                       InputError);
  CHECK_THROWS_AS(d->assemble(mesh, nf, Config::from_key_values({"mass=consistent"})), InputError);
  // one corner normal inconsistent with the orientation: policy error throws, warn reports
  nf.vertex.row(1) = Eigen::RowVector3d(-0.1, 1, 0).normalized();
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config::from_key_values({"orientation=error"})),
                       doctest::Contains("face 0 corner 1"), InputError);
  const Operators w = d->assemble(mesh, nf, Config());
  REQUIRE(!w.warnings.empty());
  CHECK(w.warnings[0].find("1 of 4 face corners") != std::string::npos);
  // all normals flipped: rejected under every policy
  nf.vertex = -Eigen::MatrixX3d::Zero(4, 3);
  nf.vertex.col(0).setConstant(-1.0);
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config::from_key_values({"orientation=warn"})),
                       doctest::Contains("flipped"), InputError);
}

TEST_CASE("corrected VRM reports a non-convergent minimizer (warning, or NumericalError under policy error)") {
  SurfelMesh mesh = test::single_surfel(0.5);
  NormalFields nf;
  nf.vertex.resize(4, 3);
  nf.vertex << 1, 0.2, -0.1, 0.9, -0.3, 0.2, 1, 0.1, 0.3, 0.8, 0.4, 0.1;  // docs/math.md §12.2 regression normals
  nf.vertex.rowwise().normalize();
  const auto d = make_discretization("corrected-vrm");
  const Operators ok = d->assemble(mesh, nf, Config());
  CHECK(ok.warnings.empty());
  const Operators w = d->assemble(mesh, nf, Config::from_key_values({"max_iterations=1"}));
  REQUIRE(w.warnings.size() == 1);
  CHECK(w.warnings[0].find("did not converge on 1 of 1 faces (worst: face 0") != std::string::npos);
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config::from_key_values({"max_iterations=1", "orientation=error"})),
                       doctest::Contains("did not converge"), NumericalError);
}

TEST_CASE("VRM skips degenerate fan triangles and reports them") {
  // a quad whose corner 2 coincides with corner 1: fan triangle (x1, x2, p) has zero area
  QuadPositions X;
  X << 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0;
  const VrmLocal loc = vrm_local(X);
  CHECK(loc.skipped_triangles == 1);
  CHECK(loc.K.allFinite());
  CHECK((loc.K * Eigen::Vector4d::Ones()).cwiseAbs().maxCoeff() < 1e-13);
  SurfelMesh mesh;
  mesh.positions = X;
  mesh.faces.resize(1, 4);
  mesh.faces << 0, 1, 2, 3;
  const Operators ops = make_discretization("vrm")->assemble(mesh, NormalFields(), Config());
  REQUIRE(ops.warnings.size() == 1);
  CHECK(ops.warnings[0].find("degenerate fan triangle") != std::string::npos);
  NormalFields nf;
  nf.vertex = Eigen::MatrixX3d::Zero(4, 3);
  nf.vertex.col(2).setOnes();
  const auto d = make_discretization("corrected-vrm");
  const Operators c = d->assemble(mesh, nf, Config());
  REQUIRE(!c.warnings.empty());
  CHECK(c.warnings.back().find("degenerate fan triangle") != std::string::npos);
  CHECK_THROWS_WITH_AS(d->assemble(mesh, nf, Config::from_key_values({"orientation=error"})),
                       doctest::Contains("degenerate"), InputError);
}

TEST_CASE(
    "corrected VRM and heat kernel: flipping face orientation and normals together changes nothing (docs/math.md "
    "§12.6)") {
  const SurfelMesh mesh = test::sphere1_surface(0.25);
  SurfelMesh flipped;
  flipped.positions = mesh.positions;  // no surfel data: trivial normals come from the corner order
  flipped.h = mesh.h;
  flipped.faces = mesh.faces;
  for (int f = 0; f < mesh.num_faces(); ++f)
    flipped.faces.row(f) << mesh.faces(f, 0), mesh.faces(f, 3), mesh.faces(f, 2), mesh.faces(f, 1);
  SurfelMesh plain = mesh;
  plain.surfels.clear();
  NormalFields nf, nf_flipped;
  nf.vertex = test::radial(mesh.positions);
  nf.face = test::radial(mesh.face_centroids());
  nf_flipped.vertex = -nf.vertex;
  nf_flipped.face = -nf.face;
  for (const char* method : {"corrected-vrm", "heat-kernel", "vrm"}) {
    CAPTURE(method);
    const auto d = make_discretization(method);
    const Operators a = d->assemble(plain, nf, Config());
    const Operators b = d->assemble(flipped, nf_flipped, Config());
    CHECK((a.L - b.L).norm() < 1e-12 * a.L.norm());
    CHECK((a.M - b.M).norm() < 1e-12 * a.M.norm());
    // flipping only the normals is rejected
    if (std::string(method) != "vrm") CHECK_THROWS_AS(d->assemble(plain, nf_flipped, Config()), InputError);
  }
}
