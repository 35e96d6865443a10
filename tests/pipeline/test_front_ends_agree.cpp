// The CLI and a study build their surface, normals and operators through the same library calls
// (load_surface, resolve_normals): for one input they agree bit for bit. tests/python/test_bindings.py
// (test_python_equals_cli_on_the_front_end_input) checks Python against the same CLI commands.
#include <doctest/doctest.h>

#include <corrlap/corrlap.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/studies/study.hpp>

#include "test_support.hpp"

using namespace corrlap;

#ifdef CORRLAP_CLI
TEST_CASE("CLI and study: sphere1, h = 0.1, II normals (alpha 1/3), fem give the same bits") {
  const std::string dir = test::tmp_path("front_ends_" + std::to_string(::getpid()));
  // 0.33333333333333331 is 1/3 to 17 digits: the study's alpha, read back exactly.
  const std::string input = " --shape sphere1 --h 0.1 --bbox -1.5 1.5";
  const std::string ii = " --normals ii --ii-radius 3 --ii-alpha 0.33333333333333331";
  std::string err;
  REQUIRE(test::run_cli("digitize" + input + " --out " + dir + "_mesh.obj", nullptr, &err) == 0);
  REQUIRE(test::run_cli("normals" + input + ii + " --out " + dir + "_fn.txt", nullptr, &err) == 0);
  REQUIRE(test::run_cli("normals" + input + ii + " --at vertices --out " + dir + "_vn.txt", nullptr, &err) == 0);
  REQUIRE(test::run_cli("operators --method fem" + input + ii + " --out " + dir + "_ops", nullptr, &err) == 0);

  StudyOptions o;
  o.normals = "ii";
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  const StudySurface s = study_surface(o, 0.1, Eigen::Vector3d::Zero());
  const PolygonMesh cli_mesh = read_mesh(dir + "_mesh.obj");  // 17 digits: exact
  CHECK(cli_mesh.positions == s.surface.mesh.positions);
  CHECK(to_surfel_mesh(cli_mesh, "cli mesh").faces == s.surface.mesh.faces);
  CHECK(read_normals(dir + "_fn.txt") == s.normals.face);
  CHECK(read_normals(dir + "_vn.txt") == s.normals.vertex);
  // The study's assembly: the registry with the shared quad pattern.
  const Operators ops =
      make_discretization("fem")->assemble(s.surface.mesh, s.normals, Config(), QuadPattern::build(s.surface.mesh));
  const Eigen::SparseMatrix<double> L = read_matrix_market(dir + "_ops/L.mtx");
  const Eigen::SparseMatrix<double> M = read_matrix_market(dir + "_ops/M.mtx");
  REQUIRE(L.nonZeros() == ops.L.nonZeros());
  CHECK((L - ops.L).norm() == 0.0);  // %.17g round-trips every double
  CHECK((M - ops.M).norm() == 0.0);
}
#endif

TEST_CASE("study_surface: the study's normals vocabulary is the library's") {
  StudyOptions o;
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  o.normals = "exact";
  CHECK(study_normal_source(o) == NormalSource::Exact);
  const StudySurface s = study_surface(o, 0.2, Eigen::Vector3d::Zero());
  CHECK(s.normals.vertex == exact_vertex_normals(*s.surface.shape, s.surface.mesh));
  o.normals = "true";
  const StudySurface t = study_surface(o, 0.2, Eigen::Vector3d::Zero());
  CHECK(t.normals.face == s.normals.face);
  CHECK(t.normals.vertex == true_vertex_normals_from_faces(*t.surface.shape, t.surface.mesh));
  o.normals = "trivial";
  CHECK_THROWS_WITH_AS(study_normal_source(o), doctest::Contains("expected true, ii or exact"), InputError);
  o.kind = StudyKind::Cotan;
  o.normals = "mesh";
  CHECK(study_normal_source(o) == NormalSource::Given);
  o.normals = "ii";
  CHECK(study_normal_source(o) == NormalSource::II);
}
