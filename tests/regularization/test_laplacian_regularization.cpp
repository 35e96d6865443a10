// The Laplacian regularization of docs/math.md §9.2: exact data is a fixed point, the result is the
// energy's minimizer, a digitized sphere moves towards the true one, bad inputs are named.
#include <doctest/doctest.h>

#include <corrlap/backends/cholmod.hpp>
#include <corrlap/corrlap.hpp>
#include <numbers>

#include "regularization/sphere_fixture.hpp"

using namespace corrlap;
using SpMat = Eigen::SparseMatrix<double>;

namespace {

struct Sphere {
  SurfelMesh mesh;
  NormalFields normals;
  Operators ops;
};

// sphere1 at h = 0.1 with true normals (sphere_fixture.hpp) and the corrected FEM.
const Sphere& sphere() {
  static const Sphere s = [] {
    const test::RegularizationSphere& base = test::regularization_sphere();
    Sphere r;
    r.mesh = base.mesh;
    r.normals = base.normals;
    r.ops = make_discretization("fem")->assemble(r.mesh, r.normals, Config());
    return r;
  }();
  return s;
}

double mean_distance_to_unit_sphere(const Eigen::MatrixX3d& p) {
  return (p.rowwise().norm().array() - 1.0).abs().mean();
}

double total_energy(const RegularizationEnergy& e, double alpha) { return e.laplacian + alpha * e.attachment; }

}  // namespace

TEST_CASE("exact data (L p = -2 M_l H n) is returned unchanged") {
  const Sphere& s = sphere();
  const Eigen::MatrixX3d& p = s.mesh.positions;
  // H n := -1/2 M_l^{-1} L p: the data that makes p exact, split into its norm and direction.
  const Eigen::VectorXd mass = lumped_mass(s.ops.M).diagonal();
  const Eigen::MatrixX3d Hn = -0.5 * (mass.cwiseInverse().asDiagonal() * (s.ops.L * p));
  const Eigen::VectorXd H = Hn.rowwise().norm();
  REQUIRE(H.minCoeff() > 0.0);
  const Eigen::MatrixX3d n = H.cwiseInverse().asDiagonal() * Hn;
  auto solver = make_linear_solver("cholmod");
  const Eigen::MatrixX3d q = regularize_positions(s.ops.L, s.ops.M, p, n, H, regularization_alpha(0.1), *solver);
  // A backward-stable solve of a system with condition ~1e4 (alpha M_l vs L M_l^{-1} L): ~1e-12.
  CHECK((q - p).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("the result minimizes the energy, and a digitized sphere moves towards the unit sphere") {
  const Sphere& s = sphere();
  const Eigen::MatrixX3d& p = s.mesh.positions;
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());  // the unit sphere: Delta p = -2 p
  const Eigen::MatrixX3d& n = s.normals.vertex;
  const double alpha = regularization_alpha(0.1);
  auto solver = make_linear_solver("cholmod");
  const Eigen::MatrixX3d q = regularize_positions(s.ops.L, s.ops.M, p, n, H, alpha, *solver);
  const double at_q = total_energy(regularization_energy(s.ops.L, s.ops.M, p, n, H, q), alpha);
  CHECK(at_q < total_energy(regularization_energy(s.ops.L, s.ops.M, p, n, H, p), alpha));
  // A quadratic's minimizer: any perturbation raises the energy.
  std::srand(4);
  for (double eps : {1e-3, 1e-5}) {
    const Eigen::MatrixX3d d = eps * Eigen::MatrixX3d::Random(p.rows(), 3);
    CHECK(at_q < total_energy(regularization_energy(s.ops.L, s.ops.M, p, n, H, q + d), alpha));
  }
  const double before = mean_distance_to_unit_sphere(p), after = mean_distance_to_unit_sphere(q);
  MESSAGE("sphere1 h = 0.1, fem, true normals, H = 1: mean distance " << before << " -> " << after);
  // Pointels lie on the staircase, ~h/4 off the sphere on average; the regularized positions
  // must be several times closer (the paper's Fig. 13 shows an order of magnitude).
  CHECK(after < 0.25 * before);
}

TEST_CASE("bad inputs are named") {
  const Sphere& s = sphere();
  const Eigen::MatrixX3d& p = s.mesh.positions;
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());
  const Eigen::MatrixX3d& n = s.normals.vertex;
  auto solver = make_linear_solver("cholmod");
  const auto message = [&](const SpMat& L, const SpMat& M, const Eigen::MatrixX3d& pp, const Eigen::MatrixX3d& nn,
                           const Eigen::VectorXd& HH, double alpha) -> std::string {
    try {
      regularize_positions(L, M, pp, nn, HH, alpha, *solver);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  Eigen::VectorXd nan_H = H;
  nan_H[7] = std::nan("");
  CHECK(message(s.ops.L, s.ops.M, p, n, nan_H, 1.0).find("mean curvature of vertex 7 is nan") != std::string::npos);
  Eigen::MatrixX3d flat_n = n;
  flat_n.row(3) *= 2.0;
  CHECK(message(s.ops.L, s.ops.M, p, flat_n, H, 1.0).find("normal of vertex 3 is not a unit vector") !=
        std::string::npos);
  CHECK(message(s.ops.L, s.ops.M, p, n, H.head(5), 1.0).find("H is 5 x 1") != std::string::npos);
  CHECK(message(s.ops.L, s.ops.M, p, n, H, 0.0).find("alpha must be a positive number") != std::string::npos);
  SpMat no_mass = s.ops.M;
  no_mass.coeffRef(0, 0) = -1e6;
  CHECK(message(s.ops.L, no_mass, p, n, H, 1.0).find("vertex 0 has mass") != std::string::npos);
  CHECK_THROWS_AS(regularization_alpha(0.0), InputError);
}

TEST_CASE("regularize_surface: H = +1 on the unit sphere, the surface gets closer, faces kept, bad inputs named") {
  const Sphere& s = sphere();
  const RegularizedSurface r = regularize_surface(s.mesh, s.normals);
  // The corrected mean curvature with exact normals at h = 0.1: within a few percent of 1
  // (docs/math.md §12.4 gives mean H 1.0026, max |H - 1| 0.045 on this surface).
  CHECK(r.H.mean() == doctest::Approx(1.0).epsilon(0.01));
  CHECK(r.mesh.faces == s.mesh.faces);
  CHECK(r.h == doctest::Approx(0.1));
  // Size: half the longest side of the pointels' box, 1 + h/2 for the digitized unit sphere.
  CHECK(r.size == doctest::Approx(1.05).epsilon(1e-9));
  CHECK(r.alpha == doctest::Approx(10.0 / (0.1 * 1.05 * 0.1 * 1.05)));
  CHECK(r.curvature_radius == doctest::Approx(0.105));
  CHECK(r.energy_after.laplacian < r.energy_before.laplacian);
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const SurfaceQuality before = measure_against_shape(s.mesh, shape, 0.1);
  const SurfaceQuality after = measure_against_shape(r.mesh, shape, 0.1);
  MESSAGE("distance " << before.distance_l1 << " -> " << after.distance_l1 << ", angle " << before.normal_angle_deg
                      << " -> " << after.normal_angle_deg << " deg, |H - 1| " << before.mean_curvature_error << " -> "
                      << after.mean_curvature_error);
  CHECK(after.distance_l1 < 0.25 * before.distance_l1);
  CHECK(after.normal_angle_deg < 0.25 * before.normal_angle_deg);
  CHECK(after.mean_curvature_error < 0.25 * before.mean_curvature_error);
  // The default (cholmod) takes the preconditioned scheme; "cg" the normal equations, same result.
  CHECK(r.solve_scheme == "preconditioned-cg");
  CHECK(r.solve_iterations > 0);
  RegularizationOptions with_cg;
  with_cg.solver.set("solver", "cg");
  with_cg.solver.set("tolerance", 1e-12);
  const RegularizedSurface rc = regularize_surface(s.mesh, s.normals, with_cg);
  CHECK(rc.solve_scheme == "direct");
  // Solved to rounding, the preconditioned scheme gives the direct solution.
  RegularizationOptions to_rounding;
  to_rounding.solve_accuracy = 0.0;
  const RegularizedSurface r0 = regularize_surface(s.mesh, s.normals, to_rounding);
  CHECK((rc.mesh.positions - r0.mesh.positions).cwiseAbs().maxCoeff() < 1e-8);
  // With the default accuracy, within the bound it reports (area-weighted RMS per coordinate).
  {
    const Eigen::VectorXd mass =
        lumped_mass(make_discretization("fem")->assemble(s.mesh, s.normals, Config()).M).diagonal();
    const double h = s.mesh.grid_step();
    CHECK(r.solve_error_bound <= kRegularizationSolveAccuracy);
    for (Eigen::Index j = 0; j < 3; ++j) {
      const Eigen::VectorXd e = r.mesh.positions.col(j) - rc.mesh.positions.col(j);
      CHECK(std::sqrt(e.dot(mass.asDiagonal() * e) / mass.sum()) <= r.solve_error_bound * h * (1.0 + 1e-6) + 1e-10);
    }
  }

  RegularizationOptions faces;
  faces.method = "heat-kernel";
  CHECK_THROWS_WITH_AS(regularize_surface(s.mesh, s.normals, faces), doctest::Contains("on faces"), InputError);
  RegularizationOptions unknown;
  unknown.method = "nosuch";
  CHECK_THROWS_AS(regularize_surface(s.mesh, s.normals, unknown), InputError);
  // An open surface: the sphere without its first face.
  SurfelMesh open = s.mesh;
  open.faces = s.mesh.faces.bottomRows(s.mesh.num_faces() - 1);
  if (open.has_surfels()) open.surfels.erase(open.surfels.begin());
  NormalFields open_normals = s.normals;
  open_normals.face = s.normals.face.bottomRows(s.mesh.num_faces() - 1);
  CHECK_THROWS_WITH_AS(regularize_surface(open, open_normals), doctest::Contains("open (4 boundary edges)"),
                       InputError);
}

TEST_CASE("regularize_positions_preconditioned equals regularize_positions, in a few iterations") {
  const test::RegularizationSphere& base = test::regularization_sphere();
  const Eigen::MatrixX3d& p = base.mesh.positions;
  const Eigen::MatrixX3d& n = base.normals.vertex;
  std::srand(11);
  // An H with structure (not the exact one), so that the solution is not p + c n.
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows()) + 0.3 * Eigen::VectorXd::Random(p.rows());
  for (const char* method : {"fem", "interpolated", "corrected-vrm", "projected-polydec", "polydec"}) {
    CAPTURE(method);
    const Operators ops = make_discretization(method)->assemble(base.mesh, base.normals, Config());
    for (const double alpha0 : {1.0, 10.0, 1000.0}) {
      CAPTURE(alpha0);
      const double alpha = regularization_alpha(0.1, alpha0);
      auto direct = make_linear_solver("cholmod");
      const Eigen::MatrixX3d q = regularize_positions(ops.L, ops.M, p, n, H, alpha, *direct);
      auto factor = make_linear_solver("cholmod");
      SolverReport report;
      const Eigen::MatrixX3d qp = regularize_positions_preconditioned(ops.L, ops.M, p, n, H, alpha, *factor, &report);
      // Relative residual 1e-10 of A x = b with b ~ alpha M_l x: the error in x is ~1e-10 |x|
      // in the smooth modes (A's smallest eigenvalues are alpha M_l's), below in the others.
      CHECK((qp - q).cwiseAbs().maxCoeff() < 1e-8);
      CHECK(report.residual < 1e-9);
      // P^{-1} A has its spectrum in [1/2, 1]: CG's bound (sqrt 2 - 1)/(sqrt 2 + 1) per step
      // reaches 1e-10 in 14 steps; allow a margin for rounding.
      CHECK(report.iterations <= 25);
      MESSAGE(std::string(method) << " alpha0 " << alpha0 << ": " << report.iterations << " iterations");
    }
  }
}

TEST_CASE("regularize_positions_preconditioned to an accuracy: the error is within the bound it reports") {
  const test::RegularizationSphere& base = test::regularization_sphere();
  const Eigen::MatrixX3d& p = base.mesh.positions;
  const Eigen::MatrixX3d& n = base.normals.vertex;
  std::srand(12);
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows()) + 0.3 * Eigen::VectorXd::Random(p.rows());
  const double h = base.mesh.grid_step();
  for (const char* method : {"fem", "projected-polydec"}) {
    CAPTURE(method);
    const Operators ops = make_discretization(method)->assemble(base.mesh, base.normals, Config());
    const Eigen::VectorXd mass = lumped_mass(ops.M).diagonal();
    for (const double alpha0 : {1.0, 10.0, 1000.0}) {
      CAPTURE(alpha0);
      const double alpha = regularization_alpha(h, alpha0);
      auto direct = make_linear_solver("cholmod");
      const Eigen::MatrixX3d exact = regularize_positions(ops.L, ops.M, p, n, H, alpha, *direct);
      SolverReport to_rounding;
      auto factor = make_linear_solver("cholmod");
      (void)regularize_positions_preconditioned(ops.L, ops.M, p, n, H, alpha, *factor, &to_rounding);
      for (const double voxels : {1e-2, 1e-4}) {
        CAPTURE(voxels);
        SolverReport report;
        double bound = -1.0;
        auto again = make_linear_solver("cholmod");
        const Eigen::MatrixX3d q =
            regularize_positions_preconditioned(ops.L, ops.M, p, n, H, alpha, *again, &report, voxels * h, &bound);
        // The bound holds: every coordinate's area-weighted RMS error is at most the bound
        // (exact's own error, ~1e-10 |p|, is far below the accuracies asked), and the bound at most
        // the accuracy.
        for (Eigen::Index j = 0; j < 3; ++j) {
          const Eigen::VectorXd e = q.col(j) - exact.col(j);
          const double rms = std::sqrt(e.dot(mass.asDiagonal() * e) / mass.sum());
          CHECK(rms <= bound * (1.0 + 1e-6));
        }
        CHECK(bound > 0.0);
        CHECK(bound <= voxels * h);
        // It stops earlier than to rounding.
        CHECK(report.iterations < to_rounding.iterations);
      }
    }
  }
  // A negative or NaN accuracy is refused.
  const Operators ops = make_discretization("fem")->assemble(base.mesh, base.normals, Config());
  auto factor = make_linear_solver("cholmod");
  CHECK_THROWS_AS(
      regularize_positions_preconditioned(ops.L, ops.M, p, n, H, regularization_alpha(h), *factor, nullptr, -1.0),
      InputError);
}

TEST_CASE("PreconditionedRegularization: one analysis for every alpha, warm starts within the bound") {
  const test::RegularizationSphere& base = test::regularization_sphere();
  const Eigen::MatrixX3d& p = base.mesh.positions;
  const Eigen::MatrixX3d& n = base.normals.vertex;
  std::srand(13);
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows()) + 0.3 * Eigen::VectorXd::Random(p.rows());
  const double h = base.mesh.grid_step();
  const Operators ops = make_discretization("fem")->assemble(base.mesh, base.normals, Config());
  const Eigen::VectorXd mass = lumped_mass(ops.M).diagonal();
  CholmodSolver shared;
  PreconditionedRegularization repeated(ops.L, ops.M, p, n, H, shared);
  Eigen::MatrixX3d last;
  double last_alpha0 = 0.0;
  for (const double alpha0 : {10.0, 1000.0, 30.0}) {
    CAPTURE(alpha0);
    const double alpha = regularization_alpha(h, alpha0);
    // From 0, the same arithmetic as the one-shot function: equal bit for bit.
    auto fresh = make_linear_solver("cholmod");
    SolverReport one_shot_report;
    const Eigen::MatrixX3d one_shot =
        regularize_positions_preconditioned(ops.L, ops.M, p, n, H, alpha, *fresh, &one_shot_report, 1e-3 * h);
    SolverReport report;
    const Eigen::MatrixX3d q = repeated.solve(alpha, 1e-3 * h, &report);
    CHECK((q - one_shot).cwiseAbs().maxCoeff() == 0.0);
    CHECK(report.iterations == one_shot_report.iterations);
    // Only the first solve analyzed B: the others factorized the analyzed pattern again.
    CHECK(shared.analysis_count() == 1);
    if (last.rows() > 0) {
      // From the last alpha's positions: within the bound of the exact solution, as from 0.
      auto direct = make_linear_solver("cholmod");
      const Eigen::MatrixX3d exact = regularize_positions(ops.L, ops.M, p, n, H, alpha, *direct);
      double bound = -1.0;
      SolverReport warm;
      const Eigen::MatrixX3d w = repeated.solve(alpha, 1e-3 * h, &warm, &bound, &last);
      CHECK(bound > 0.0);
      CHECK(bound <= 1e-3 * h);
      for (Eigen::Index j = 0; j < 3; ++j) {
        const Eigen::VectorXd e = w.col(j) - exact.col(j);
        CHECK(std::sqrt(e.dot(mass.asDiagonal() * e) / mass.sum()) <= bound * (1.0 + 1e-6));
      }
      // A raise of alpha (the automatic alpha0's only direction) moves the solution less than
      // the shape's size: no more iterations than from 0.
      if (alpha0 > last_alpha0) CHECK(warm.iterations <= report.iterations);
    }
    last = q;
    last_alpha0 = alpha0;
  }
  // Start positions of the wrong size, or not finite, are named.
  const Eigen::MatrixX3d short_start = Eigen::MatrixX3d::Zero(3, 3);
  CHECK_THROWS_AS(repeated.solve(regularization_alpha(h), 0.0, nullptr, nullptr, &short_start), InputError);
  Eigen::MatrixX3d nan_start = p;
  nan_start(0, 0) = std::nan("");
  CHECK_THROWS_AS(repeated.solve(regularization_alpha(h), 0.0, nullptr, nullptr, &nan_start), InputError);
}

TEST_CASE("regularize_positions_preconditioned refuses an L that is not negative semi-definite") {
  const test::RegularizationSphere& base = test::regularization_sphere();
  const Eigen::MatrixX3d& p = base.mesh.positions;
  const Eigen::MatrixX3d& n = base.normals.vertex;
  const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());
  // L not negative semi-definite: B = beta M_l - L is not SPD and the factorization says so.
  const Operators ops = make_discretization("fem")->assemble(base.mesh, base.normals, Config());
  const SpMat wrong_sign = -ops.L;
  auto factor = make_linear_solver("cholmod");
  CHECK_THROWS_AS(regularize_positions_preconditioned(wrong_sign, ops.M, p, n, H, regularization_alpha(0.1), *factor),
                  SolverError);
}

TEST_CASE("enclosed_volume: the staircase holds its voxels, translations change nothing, reversed faces negate") {
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const VoxelGrid grid = digitize(shape, {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5});
  SurfelMesh mesh = extract_surface(grid);
  // A union of cubes with planar faces: exactly the voxel count times h^3 (to rounding).
  const double voxels = double(grid.count()) * 0.001;
  CHECK(enclosed_volume(mesh) == doctest::Approx(voxels).epsilon(1e-12));
  CHECK(voxels == doctest::Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.05));
  // The regularized sphere: not planar, within 1% of the ball's volume.
  const RegularizedSurface r = regularize_surface(sphere().mesh, sphere().normals);
  CHECK(enclosed_volume(r.mesh) == doctest::Approx(4.0 / 3.0 * std::numbers::pi).epsilon(0.01));
  const double before = enclosed_volume(r.mesh);
  SurfelMesh moved = r.mesh;
  moved.positions.rowwise() += Eigen::RowVector3d(3.0, -2.0, 7.0);
  CHECK(enclosed_volume(moved) == doctest::Approx(before).epsilon(1e-10));
  moved.faces = moved.faces.rowwise().reverse().eval();
  CHECK(enclosed_volume(moved) == doctest::Approx(-before).epsilon(1e-10));
}

TEST_CASE(
    "without attachment (alpha0 = 0, docs/math.md §9.3): exact data returned, a minimizer, placed per component") {
  const Sphere& s = sphere();
  const Eigen::MatrixX3d& p = s.mesh.positions;
  auto solver = make_linear_solver("cholmod");
  SUBCASE("exact data is returned unchanged: the centroid fixes the translation") {
    const Eigen::VectorXd mass = lumped_mass(s.ops.M).diagonal();
    const Eigen::MatrixX3d Hn = -0.5 * (mass.cwiseInverse().asDiagonal() * (s.ops.L * p));
    const Eigen::VectorXd H = Hn.rowwise().norm();
    REQUIRE(H.minCoeff() > 0.0);
    const Eigen::MatrixX3d n = H.cwiseInverse().asDiagonal() * Hn;
    SolverReport report;
    const Eigen::MatrixX3d q = regularize_positions_unattached(s.ops.L, s.ops.M, p, n, H, *solver, &report);
    // -L has condition ~1e3 on this surface: a backward-stable solve is within ~1e-12.
    CHECK((q - p).cwiseAbs().maxCoeff() < 1e-9);
    CHECK(report.residual < 1e-10);
  }
  SUBCASE("a minimizer of the Laplacian term, any translation of it too, and the mass-weighted centroid kept") {
    const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());
    const Eigen::MatrixX3d& n = s.normals.vertex;
    const Eigen::MatrixX3d q = regularize_positions_unattached(s.ops.L, s.ops.M, p, n, H, *solver);
    const double at_q = regularization_energy(s.ops.L, s.ops.M, p, n, H, q).laplacian;
    CHECK(at_q < regularization_energy(s.ops.L, s.ops.M, p, n, H, p).laplacian);
    std::srand(5);
    for (double eps : {1e-3, 1e-5}) {
      const Eigen::MatrixX3d d = eps * Eigen::MatrixX3d::Random(p.rows(), 3);
      CHECK(at_q < regularization_energy(s.ops.L, s.ops.M, p, n, H, q + d).laplacian);
    }
    Eigen::MatrixX3d moved = q;
    moved.rowwise() += Eigen::RowVector3d(0.3, 0.0, -0.2);
    CHECK(regularization_energy(s.ops.L, s.ops.M, p, n, H, moved).laplacian ==
          doctest::Approx(at_q).epsilon(1e-6).scale(1e-12));
    const Eigen::VectorXd mass = lumped_mass(s.ops.M).diagonal();
    const Eigen::RowVector3d centroid_p = (mass.transpose() * p) / mass.sum();
    const Eigen::RowVector3d centroid_q = (mass.transpose() * q) / mass.sum();
    CHECK((centroid_q - centroid_p).norm() < 1e-12);
    // H = 1 with unit-sphere normals: the shape is a sphere of radius ~1 whatever the attachment.
    MESSAGE("alpha0 = 0: mean distance " << mean_distance_to_unit_sphere(p) << " -> "
                                         << mean_distance_to_unit_sphere(q));
    CHECK(mean_distance_to_unit_sphere(q) < 0.25 * mean_distance_to_unit_sphere(p));
  }
  SUBCASE("the limit of the attached solution as alpha -> 0, which picks the translation nearest p") {
    // Among the minimizers p' + t, |p' + t - p|_{M_l} is least when the centroids agree: the
    // attached solutions converge to this one, the difference O(alpha).
    const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());
    const Eigen::MatrixX3d& n = s.normals.vertex;
    const Eigen::MatrixX3d q = regularize_positions_unattached(s.ops.L, s.ops.M, p, n, H, *solver);
    double previous = 1.0;
    for (const double alpha0 : {1e-2, 1e-4, 1e-6}) {
      const Eigen::MatrixX3d attached =
          regularize_positions(s.ops.L, s.ops.M, p, n, H, regularization_alpha(0.1, alpha0), *solver);
      const double gap = (attached - q).cwiseAbs().maxCoeff();
      MESSAGE("alpha0 = " << alpha0 << ": max |attached - unattached| = " << gap);
      CHECK(gap < previous);
      previous = gap;
    }
    CHECK(previous < 1e-6);
  }
  SUBCASE("two components: each solved as if alone, each at its own centroid") {
    // The sphere and a copy 5 units away, as one block-diagonal system.
    const Eigen::Index V = p.rows();
    const auto twice = [&](const SpMat& A) {
      std::vector<Eigen::Triplet<double>> t;
      for (Eigen::Index j = 0; j < A.outerSize(); ++j)
        for (SpMat::InnerIterator it(A, j); it; ++it) {
          t.emplace_back(it.row(), it.col(), it.value());
          t.emplace_back(it.row() + V, it.col() + V, it.value());
        }
      SpMat B(2 * V, 2 * V);
      B.setFromTriplets(t.begin(), t.end());
      return B;
    };
    Eigen::MatrixX3d p2(2 * V, 3), n2(2 * V, 3);
    p2 << p, p.rowwise() + Eigen::RowVector3d(5.0, 0.0, 0.0);
    n2 << s.normals.vertex, s.normals.vertex;
    const Eigen::VectorXd H2 = Eigen::VectorXd::Ones(2 * V);
    const Eigen::MatrixX3d q2 = regularize_positions_unattached(twice(s.ops.L), twice(s.ops.M), p2, n2, H2, *solver);
    const Eigen::MatrixX3d q =
        regularize_positions_unattached(s.ops.L, s.ops.M, p, s.normals.vertex, Eigen::VectorXd::Ones(V), *solver);
    CHECK((q2.topRows(V) - q).cwiseAbs().maxCoeff() < 1e-9);
    CHECK((q2.bottomRows(V) - (q.rowwise() + Eigen::RowVector3d(5.0, 0.0, 0.0))).cwiseAbs().maxCoeff() < 1e-9);
  }
  SUBCASE("an L that is not negative semi-definite is named") {
    const Eigen::VectorXd H = Eigen::VectorXd::Ones(p.rows());
    const SpMat wrong_sign = -s.ops.L;
    CHECK_THROWS_WITH_AS(regularize_positions_unattached(wrong_sign, s.ops.M, p, s.normals.vertex, H, *solver),
                         doctest::Contains("alpha0 = 0) needs L negative semi-definite"), SolverError);
  }
}

TEST_CASE("regularize_surface with alpha0 = 0: the unattached scheme, close to the sphere, a negative alpha0 named") {
  RegularizationOptions o;
  o.alpha0 = 0.0;
  const RegularizedSurface r = regularize_surface(sphere().mesh, sphere().normals, o);
  CHECK(r.solve_scheme == "unattached");
  CHECK(r.alpha == 0.0);
  CHECK(r.solve_residual < 1e-10);
  const double before = mean_distance_to_unit_sphere(sphere().mesh.positions);
  const double after = mean_distance_to_unit_sphere(r.mesh.positions);
  MESSAGE("sphere1 h = 0.1, fem, alpha0 = 0: mean distance " << before << " -> " << after);
  CHECK(after < 0.5 * before);
  o.alpha0 = -1.0;
  CHECK_THROWS_WITH_AS(regularize_surface(sphere().mesh, sphere().normals, o),
                       doctest::Contains("alpha0 = -1: alpha0 must be a finite number >= 0"), InputError);
}
