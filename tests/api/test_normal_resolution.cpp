// resolve_normals: one definition of every normal field, the same in the library and every command.
#include <doctest/doctest.h>

#include <corrlap/corrlap.hpp>

#include "test_support.hpp"

using namespace corrlap;

namespace {
const std::string kRef = test::reference_dir() + "/sphere1_h0.2/";
struct Sphere {
  ImplicitShape shape = make_implicit_shape("sphere1");
  VoxelGrid grid;
  SurfelMesh mesh;
};
const Sphere& sphere() {
  static const Sphere s = [] {
    Sphere r;
    r.grid = digitize(r.shape, {.h = 0.2, .min_aabb = -1.5, .max_aabb = 1.5});
    r.mesh = extract_surface(r.grid);
    return r;
  }();
  return s;
}
NormalRequest from(NormalSource source) {
  NormalRequest r;
  r.source = source;
  return r;
}
}  // namespace

TEST_CASE("true vertex normals are the normalized sum of the true face normals (docs/math.md §1.5, reference data)") {
  const Sphere& s = sphere();
  const NormalFields n = resolve_normals(s.mesh, NormalKind::Vertex, from(NormalSource::True), &s.shape, &s.grid);
  const Eigen::MatrixX3d expected =
      vertex_normals_from_face_normals(true_face_normals(s.shape, s.mesh), s.mesh.faces, s.mesh.num_vertices());
  CHECK(n.vertex == expected);  // bit for bit
  CHECK(true_vertex_normals_from_faces(s.shape, s.mesh) == expected);
  CHECK((n.vertex - read_normals(kRef + "vertex_normals_true.txt")).cwiseAbs().maxCoeff() < 1e-14);
  CHECK((n.face - read_normals(kRef + "face_normals_true.txt")).cwiseAbs().maxCoeff() < 1e-14);
  // Auto on a shape is True; the exact normal at the vertex is another, clearly named field.
  CHECK(resolve_normals(s.mesh, NormalKind::Vertex, {}, &s.shape, &s.grid).vertex == expected);
  const double gap = (exact_vertex_normals(s.shape, s.mesh) - expected).rowwise().norm().maxCoeff();
  CHECK(gap > 1e-3);  // the two definitions differ by a visible angle at h = 0.2
  CHECK(gap < 0.2);
}

TEST_CASE("resolve_normals: sources, files first, need None, errors naming what is missing") {
  const Sphere& s = sphere();
  // II with its parameters (reference II normals use alpha = 1/3).
  NormalRequest ii = from(NormalSource::II);
  ii.ii = IIParams{.k = 3.0, .alpha = 1.0 / 3.0};
  const NormalFields n_ii = resolve_normals(s.mesh, NormalKind::Face, ii, nullptr, &s.grid);
  CHECK((n_ii.face - read_normals(kRef + "face_normals_ii.txt")).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(!n_ii.has_vertex());
  // Auto without a shape but with voxels: II.
  NormalRequest autoii;
  autoii.ii = IIParams{.k = 3.0, .alpha = 1.0 / 3.0};
  CHECK(resolve_normals(s.mesh, NormalKind::Face, autoii, nullptr, &s.grid).face == n_ii.face);
  // Unset II parameters: the paper's with a shape, kVoxelIIRadius voxels without one.
  NormalRequest defaults = from(NormalSource::II);
  CHECK(resolve_normals(s.mesh, NormalKind::Face, defaults, &s.shape, &s.grid).face ==
        ii_face_normals(s.grid, s.mesh, IIParams{}));
  CHECK(resolve_normals(s.mesh, NormalKind::Face, defaults, nullptr, &s.grid).face ==
        ii_face_normals(s.grid, s.mesh, IIParams{.k = kVoxelIIRadius, .alpha = 1.0}));
  // Trivial: surfel normals, vertex normals from them.
  const NormalFields tr = resolve_normals(s.mesh, NormalKind::Vertex, from(NormalSource::Trivial));
  CHECK(tr.face == s.mesh.face_normals_from_positions());
  CHECK(tr.vertex == vertex_normals_from_face_normals(tr.face, s.mesh.faces, s.mesh.num_vertices()));
  CHECK(resolve_normals(s.mesh, NormalKind::None, from(NormalSource::True), &s.shape).face.rows() == 0);
  // A face file gives the vertex normals too; a vertex file is taken as is, before any source.
  NormalRequest ff = from(NormalSource::Trivial);
  ff.face_normals_file = kRef + "face_normals_ii.txt";
  const NormalFields from_file = resolve_normals(s.mesh, NormalKind::Vertex, ff);
  CHECK(from_file.vertex ==
        vertex_normals_from_face_normals(read_normals(ff.face_normals_file), s.mesh.faces, s.mesh.num_vertices()));
  NormalRequest vf = from(NormalSource::True);
  vf.vertex_normals_file = kRef + "vertex_normals_true.txt";
  CHECK(resolve_normals(s.mesh, NormalKind::Vertex, vf, &s.shape).vertex == read_normals(vf.vertex_normals_file));
  // Errors.
  CHECK_THROWS_WITH_AS(
      resolve_normals(s.mesh, NormalKind::Vertex, {}, nullptr, nullptr, "interpolated"),
      doctest::Contains("interpolated needs vertex normals: give vertex_normals, face_normals or a normals "
                        "source (true, ii, trivial)"),
      InputError);
  CHECK_THROWS_WITH_AS(resolve_normals(s.mesh, NormalKind::Face, from(NormalSource::True)),
                       doctest::Contains("implicit shape"), InputError);
  SurfelMesh no_surfels = s.mesh;
  no_surfels.surfels.clear();
  CHECK_THROWS_WITH_AS(resolve_normals(no_surfels, NormalKind::Face, from(NormalSource::II), nullptr, &s.grid),
                       doctest::Contains("need voxels"), InputError);
  NormalRequest wrong;
  wrong.vertex_normals_file = kRef + "face_normals_true.txt";
  CHECK_THROWS_WITH_AS(resolve_normals(s.mesh, NormalKind::Vertex, wrong), doctest::Contains("expected 440"),
                       InputError);
  NormalRequest vonly;
  vonly.vertex_normals_file = kRef + "vertex_normals_true.txt";
  CHECK_THROWS_WITH_AS(resolve_normals(s.mesh, NormalKind::Face, vonly, nullptr, nullptr, "fem"),
                       doctest::Contains("fem needs face normals"), InputError);
  // "exact" joined the sources (it was the studies' own name); the names are listed on a typo.
  CHECK(parse_normal_source("exact") == NormalSource::Exact);
  CHECK_THROWS_WITH_AS(parse_normal_source("exakt"), doctest::Contains("auto, true, exact, ii, trivial"), InputError);
}

#ifdef CORRLAP_CLI
TEST_CASE("--normals true: operators and solve build the same interpolated operator as the library") {
  const Sphere& s = sphere();
  const std::string common = " --method interpolated --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals true";
  const std::string dir = test::tmp_path("api_ops_true_" + std::to_string(::getpid()));
  const std::string g_file = dir + "_g.txt";
  std::string err;
  REQUIRE(test::run_cli("operators" + common + " --out " + dir, nullptr, &err) == 0);
  REQUIRE(test::run_cli("solve" + common + " --rhs x2 --out " + g_file, nullptr, &err) == 0);
  // The library path both commands call.
  const NormalFields n = resolve_normals(s.mesh, NormalKind::Vertex, from(NormalSource::True), &s.shape, &s.grid);
  const Operators lib = interpolated(s.mesh, n.vertex);
  const Eigen::SparseMatrix<double> L = read_matrix_market(dir + "/L.mtx"), M = read_matrix_market(dir + "/M.mtx");
  CHECK((L - lib.L).norm() == 0.0);  // %.17g round-trips every double
  CHECK((M - lib.M).norm() == 0.0);
  // solve's solution is the one of that operator (CHOLMOD on the same matrix: rounding only).
  auto solver = make_linear_solver();
  const PoissonResult r = solve_poisson(lib, s.mesh.positions, test_function("x2"), *solver);
  CHECK((read_scalars(g_file) - r.g).lpNorm<Eigen::Infinity>() < 1e-12);
  // The same flag in eigs: the smallest nonzero eigenvalue of that operator (dense, 440 unknowns).
  std::string out;
  REQUIRE(test::run_cli("eigs" + common + " -k 2", &out, &err) == 0);
  const EigenResult e = make_eigen_solver("dense")->solve(lib.L, lib.M, 2);
  CHECK(std::stod(out.substr(out.find('\n') + 1)) == doctest::Approx(e.values[1]).epsilon(1e-12));
}
#endif
