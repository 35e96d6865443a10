// The alignment baseline of docs/math.md §9.1 reproduces the reference's test (goursat, h = 1,
// convolved trivial normals: E 1684.340 -> 4.7763), and the convolved trivial normals behave.
#include <doctest/doctest.h>

#include <corrlap/corrlap.hpp>
#include <corrlap/estimators/convolved_trivial_normals.hpp>
#include <corrlap/regularization/alignment_regularization.hpp>

#include "test_support.hpp"

using namespace corrlap;

namespace {
SurfelMesh goursat() { return extract_surface(digitize(make_implicit_shape("goursat"), {.h = 1.0})); }
}  // namespace

TEST_CASE("alignment regularization reproduces the reference's test (goursat, h = 1, convolved trivial normals)") {
  const SurfelMesh mesh = goursat();
  REQUIRE(mesh.num_faces() == 2454);
  const Eigen::MatrixX3d n = convolved_trivial_normals(mesh);
  const AlignmentResult r = alignment_regularization(mesh, n);
  // The reference's test prints 1684.340 and 4.7763 (Catch's Approx: relative 1.2e-5 around them).
  CHECK(r.energy_initial == doctest::Approx(1684.340).epsilon(1e-6));
  CHECK(r.energy_final == doctest::Approx(4.7763).epsilon(1e-5));
  CHECK(r.iterations < 200);  // stopped by the step falling below epsilon
  CHECK(alignment_energy(mesh, n, mesh.positions, mesh.positions) == doctest::Approx(r.energy_initial));
  // The clamped variant keeps every pointel within half a voxel of where it was.
  AlignmentParams clamped;
  clamped.clamp = true;
  const AlignmentResult c = alignment_regularization(mesh, n, clamped);
  CHECK((c.positions - mesh.positions).cwiseAbs().maxCoeff() <= 0.5 + 1e-12);
  CHECK(c.energy_final < c.energy_initial);
}

TEST_CASE("alignment_minimizer: the exact minimum of E, below the reference's descent") {
  const SurfelMesh mesh = goursat();
  const Eigen::MatrixX3d n = convolved_trivial_normals(mesh);
  auto solver = make_linear_solver("cholmod");
  const AlignmentResult direct = alignment_minimizer(mesh, n, *solver);
  const AlignmentResult descent = alignment_regularization(mesh, n);
  MESSAGE("E: descent " << descent.energy_final << ", exact minimum " << direct.energy_final);
  CHECK(direct.energy_initial == doctest::Approx(descent.energy_initial));
  CHECK(direct.energy_final < descent.energy_final);
  CHECK(direct.energy_final == doctest::Approx(alignment_energy(mesh, n, mesh.positions, direct.positions)));
  // A quadratic's minimum: perturbations raise E (by d^T H d > 0, far above round-off here).
  std::srand(2);
  for (double eps : {1e-2, 1e-4}) {
    const Eigen::MatrixX3d d = eps * Eigen::MatrixX3d::Random(mesh.num_vertices(), 3);
    CHECK(alignment_energy(mesh, n, mesh.positions, direct.positions + d) > direct.energy_final);
  }
}

TEST_CASE("convolved trivial normals: unit, outward, closer to the true normals than the trivial ones") {
  const ImplicitShape sphere = make_implicit_shape("sphere1");
  const SurfelMesh mesh = extract_surface(digitize(sphere, {.h = 0.1, .min_aabb = -1.5, .max_aabb = 1.5}));
  const Eigen::MatrixX3d n = convolved_trivial_normals(mesh);
  const Eigen::MatrixX3d t = mesh.face_normals_from_positions();
  const Eigen::MatrixX3d truth = true_face_normals(sphere, mesh);
  double convolved = 0, trivial = 0, worst = 1.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    CHECK(n.row(f).norm() == doctest::Approx(1.0));
    // Outward: on the side of the true normal (a surfel's own trivial normal can be almost
    // orthogonal to the surface, on the rare risers of a nearly flat staircase).
    worst = std::min(worst, n.row(f).dot(truth.row(f)));
    convolved += std::acos(std::min(1.0, n.row(f).dot(truth.row(f))));
    trivial += std::acos(std::min(1.0, t.row(f).dot(truth.row(f))));
  }
  CHECK(worst > 0.5);
  MESSAGE("smallest n . n_true " << worst << "; mean angle to the true normals: trivial " << trivial / mesh.num_faces()
                                 << ", convolved " << convolved / mesh.num_faces() << " rad");
  CHECK(convolved < 0.5 * trivial);
  CHECK_THROWS_AS(convolved_trivial_normals(mesh, 0.0), InputError);
}

TEST_CASE("regularize --baseline alignment: the reference's energies in metrics.json, open surfaces refused") {
  const std::string dir = corrlap::test::tmp_path("regularize_alignment");
  std::string err;
  REQUIRE(
      corrlap::test::run_cli("regularize --shape goursat --h 1 --baseline alignment --normals convolved --out " + dir,
                             nullptr, &err) == 0);
  const std::string metrics = corrlap::test::read_text(dir + "/metrics.json");
  CHECK(metrics.find("\"energy_initial\": 1684.34") != std::string::npos);
  CHECK(metrics.find("\"energy_final\": 4.7763") != std::string::npos);
  SurfelMesh open = goursat();
  open.faces = open.faces.bottomRows(open.num_faces() - 1).eval();
  CHECK_THROWS_WITH_AS(alignment_regularization(open, open.face_normals_from_positions()), doctest::Contains("open"),
                       InputError);
}
