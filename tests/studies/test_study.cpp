// corrlap study (studies/study.hpp, study_tables.hpp, apps/corrlap/cmd_study.cpp): a tiny study's
// rows, tables and fitted orders; docs/math.md §12.5 at centre 0; centre draws; resume; bad options; the
// cotan comparison on a refined icosahedron (cotan_reference.hpp).
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/studies/cotan_reference.hpp>
#include <corrlap/studies/study.hpp>
#include <corrlap/studies/study_tables.hpp>
#include <filesystem>
#include <string>

#include "surface/icosahedron.hpp"
#include "test_support.hpp"

using namespace corrlap;

namespace {
StudyOptions tiny(StudyKind kind) {
  StudyOptions o;
  o.kind = kind;
  o.methods = {"fem", "interpolated"};
  o.h = {0.2, 0.1, 0.05};
  o.functions = {"x2", "expx"};
  o.centers = 2;
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  return o;
}
std::vector<StudyRow> run_rows(const StudyOptions& o) {
  std::vector<StudyRow> rows;
  StudyCallbacks cb;
  cb.rows = [&](const std::vector<StudyRow>& r) { rows.insert(rows.end(), r.begin(), r.end()); };
  run_study(o, cb);
  return rows;
}
}  // namespace

TEST_CASE("grid steps: lists and log-spaced ranges, bad text is named") {
  CHECK(parse_grid_steps("0.1,0.05") == std::vector<double>{0.1, 0.05});
  const std::vector<double> r = parse_grid_steps("0.1:0.0125:4");
  REQUIRE(r.size() == 4);
  CHECK(r == std::vector<double>{0.1, 0.05, 0.025, 0.0125});  // exactly the typed values
  for (const char* bad : {"", "0", "-0.1", "0.1,abc", "0.1:0.01", "0.1:0.01:0", "0.1:0.01:x", "inf"}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH_AS(parse_grid_steps(bad), doctest::Contains("grid steps"), InputError);
  }
}

TEST_CASE("centre offsets: 0 for one centre, reproducible uniform draws in [-1/2, 1/2]^3 otherwise") {
  CHECK(study_center_offset(1, 0, 1).isZero());
  for (int i = 0; i < 64; ++i) {
    const Eigen::Vector3d o = study_center_offset(7, i, 64);
    CHECK(o.cwiseAbs().maxCoeff() <= 0.5);
    CHECK(o == study_center_offset(7, i, 64));
  }
  CHECK(study_center_offset(7, 3, 64) != study_center_offset(8, 3, 64));
  CHECK(study_center_offset(7, 3, 64) != study_center_offset(7, 4, 64));
}

TEST_CASE("backward study at centre 0 reproduces docs/math.md §12.5 (FEM, true normals) to the printed digits") {
  StudyOptions o;
  o.kind = StudyKind::Backward;
  o.methods = {"fem"};
  o.h = {0.2};
  o.functions = {"x2", "expx", "p6"};
  const std::vector<StudyRow> rows = run_rows(o);
  REQUIRE(rows.size() == 3);
  // docs/math.md §12.5: 0.0204, 0.0351, 0.0791 (three digits: tolerance half a unit of the last one).
  CHECK(std::abs(rows[0].error_l2 - 0.0204) < 0.00005);
  CHECK(std::abs(rows[1].error_l2 - 0.0351) < 0.00005);
  CHECK(std::abs(rows[2].error_l2 - 0.0791) < 0.00005);
  o.kind = StudyKind::Forward;  // diffused forward L_inf: 0.374, 0.584, 5.39
  const std::vector<StudyRow> fwd = run_rows(o);
  CHECK(std::abs(fwd[0].error_linf - 0.374) < 0.0005);
  CHECK(std::abs(fwd[1].error_linf - 0.584) < 0.0005);
  // 5.38496 here; docs/math.md §12.5 prints 5.39 (one unit of its last digit away: a double rounding there).
  CHECK(std::abs(fwd[2].error_linf - 5.39) < 0.01);
}

TEST_CASE("a tiny backward study: one row per (method, function, h, centre), tables and orders") {
  const StudyOptions o = tiny(StudyKind::Backward);
  const std::vector<StudyRow> rows = run_rows(o);
  CHECK(rows.size() == 2 * 2 * 3 * 2);
  for (const StudyRow& r : rows) {
    CHECK(r.error_l2 > 0);
    CHECK(r.error_linf >= r.error_l2);  // the M-weighted mean square is at most the maximum
    CHECK(r.c.cwiseAbs().maxCoeff() <= r.h / 2);
  }
  const std::vector<SummaryRow> summary = summarize(rows);
  CHECK(summary.size() == 2 * 2 * 3);
  CHECK(summary[0].centers == 2);
  CHECK(summary[0].l2_std > 0);  // two different centres
  const std::vector<OrderRow> orders = fit_orders(rows);
  CHECK(orders.size() == 2 * 2 * 2);
  for (const OrderRow& r : orders) {
    CAPTURE(r.method);
    CAPTURE(r.function);
    CAPTURE(r.norm);
    // Sanity band of a working study (backward < 1.4 means broken); the paper's ~1.9 is
    // asymptotic, these are three coarse steps, 0.2 -> 0.05.
    CHECK(r.order > 1.4);
    CHECK(r.order < 3.0);
    CHECK(r.low < r.order);
    CHECK(r.high > r.order);
    CHECK(r.points == 6);
    CHECK(r.h_min == 0.05);
    CHECK(r.h_max == 0.2);
  }
  // Orders of exact power laws are recovered exactly, with a zero-width interval.
  std::vector<StudyRow> synthetic;
  for (double h : {0.1, 0.05, 0.025})
    for (int c = 0; c < 2; ++c) {
      // Designated initializers construct the strings (assigning "m" to a fresh string trips a
      // false -Wrestrict of GCC 12's inlined std::string::assign).
      StudyRow r{.study = "backward", .method = "m", .normals = {}, .function = "x2", .h = h, .center = c};
      r.error_linf = 3.0 * h;
      r.error_l2 = 0.5 * h * h;
      synthetic.push_back(r);
    }
  const std::vector<OrderRow> exact = fit_orders(synthetic);
  REQUIRE(exact.size() == 2);
  CHECK(exact[0].order == doctest::Approx(1.0));
  CHECK(exact[1].order == doctest::Approx(2.0));
  CHECK(exact[1].high - exact[1].low == doctest::Approx(0.0).epsilon(1e-9));
  CHECK(student_t_975(4) == doctest::Approx(2.776));
  CHECK(student_t_975(1000) == doctest::Approx(1.962).epsilon(1e-3));
}

TEST_CASE("an eigen study: 49 values per unit against l(l+1), corrected methods accurate at low l") {
  StudyOptions o;
  o.kind = StudyKind::Eigen;
  o.methods = {"fem"};
  o.h = {0.1};
  o.k = 16;
  std::vector<EigenRow> rows;
  StudyCallbacks cb;
  cb.eigen_rows = [&](const std::vector<EigenRow>& r) { rows.insert(rows.end(), r.begin(), r.end()); };
  run_study(o, cb);
  REQUIRE(rows.size() == 16);
  CHECK(std::isnan(rows[0].relative_error));
  CHECK(std::abs(rows[0].computed) < 1e-8);
  CHECK(rows[1].exact == 2.0);
  CHECK(rows[4].exact == 6.0);
  CHECK(rows[15].exact == 12.0);
  for (int i = 1; i < 16; ++i) CHECK(std::abs(rows[std::size_t(i)].relative_error) < 0.02);
}

TEST_CASE("study options: unknown method, function or study, bad h lists and keys are named") {
  StudyOptions o = tiny(StudyKind::Backward);
  o.methods = {"fem", "nosuch"};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("nosuch"), InputError);
  o = tiny(StudyKind::Backward);
  o.functions = {"x3"};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("x3"), InputError);
  o = tiny(StudyKind::Backward);
  o.h = {};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("empty"), InputError);
  o.h = {0.1, -0.05};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("must be positive"), InputError);
  o = tiny(StudyKind::Backward);
  o.method_params = {"no_such_key=1"};
  CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("no_such_key"), InputError);
  CHECK_THROWS_WITH_AS(parse_study_kind("sideways"), doctest::Contains("forward, backward, eigen or cotan"),
                       InputError);
}

namespace {
// An icosahedron as an OBJ file: the cotan study's reference after Loop subdivision.
std::string icosahedron_obj() {
  const std::string path = test::tmp_path("icosahedron.obj");
  const TriangleMesh ico = test::icosahedron();
  PolygonMesh m;
  m.positions = ico.positions;
  for (Eigen::Index f = 0; f < ico.triangles.rows(); ++f)
    m.faces.push_back({ico.triangles(f, 0), ico.triangles(f, 1), ico.triangles(f, 2)});
  write_mesh(path, m);
  return path;
}
}  // namespace

TEST_CASE("cotan study: the refined, rescaled reference, sampling at its vertices, errors shrink with N") {
  const std::string path = icosahedron_obj();
  const std::vector<const TestFunction*> x2 = {&test_function("x2")};
  const CotanReference ref = make_cotan_reference(read_mesh(path), x2, 2500);
  CHECK(ref.subdivision_steps == 4);
  CHECK(ref.positions.rows() == 2562);
  CHECK(ref.scale == doctest::Approx((1 + std::sqrt(5.0)) / 2));  // longest side 2t -> 2
  // Sampling exactly at the reference's vertices gives back the vertex values and normals.
  const ReferenceSamples own = sample_reference(ref, ref.laplacian, ref.positions);
  CHECK((own.f - ref.f).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((own.laplacian - ref.laplacian).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((own.normals - ref.normals).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(own.max_distance < 1e-12);
  // The diffused truth with dt = 0 is the plain one.
  CHECK(diffused_reference_laplacian(ref, 0.0) == ref.laplacian);

  StudyOptions o;
  o.kind = StudyKind::Cotan;
  o.mesh_file = path;
  o.resolutions = {12, 24};
  o.refine_vertices = 2500;
  o.methods = {"fem"};
  o.functions = {"x2"};
  o.normals = "mesh";
  o.reference_laplacian = "diffused";
  const std::vector<StudyRow> rows = run_rows(o);
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].study == "cotan");
  CHECK(rows[0].h == 2.0 / 12);
  CHECK(rows[1].h == 2.0 / 24);
  MESSAGE("cotan study, icosahedron refined to 2562 vertices, fem, x2: L2 " << rows[0].error_l2 << " (N = 12), "
                                                                            << rows[1].error_l2 << " (N = 24)");
  // Forward with diffusion converges at order ~1: halving h must cut the error clearly.
  CHECK(rows[1].error_l2 < rows[0].error_l2 / 1.4);

  StudyOptions bad = o;
  bad.mesh_file = "";
  CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("no mesh"), InputError);
  bad = o;
  bad.resolutions = {2};
  CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("[4, 4096]"), InputError);
  bad = o;
  bad.normals = "true";
  CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("expected mesh"), InputError);
  bad = o;
  bad.kind = StudyKind::Forward;
  bad.normals = "mesh";
  CHECK_THROWS_WITH_AS(bad.validate(), doctest::Contains("belong to the cotan study"), InputError);
  bad = o;
  bad.mesh_file = test::tmp_path("no-such-mesh.obj");
  CHECK_THROWS_AS(run_rows(bad), InputError);
}

#ifdef CORRLAP_CLI
TEST_CASE("corrlap study: CSV files with the documented columns, resume without recomputation, bad options") {
  const std::string dir = test::tmp_path("study_cli");
  std::filesystem::remove_all(dir);
  const std::string args =
      "study backward --methods fem,interpolated --h 0.4,0.3 --functions x2 --centers 2 --bbox -1.5 1.5 --no-plots "
      "--out " +
      dir;
  std::string out, err;
  REQUIRE(test::run_cli(args, &out, &err) == 0);
  CHECK(test::read_text(dir + "/results.csv")
            .rfind("study,method,normals,function,h,center,cx,cy,cz,vertices,faces,error_linf,error_l2,time_s\n", 0) ==
        0);
  CHECK(test::read_text(dir + "/summary.csv")
            .rfind("study,method,normals,function,h,centers,error_linf_mean,error_linf_std,error_l2_mean,"
                   "error_l2_std\n",
                   0) == 0);
  CHECK(test::read_text(dir + "/orders.csv")
            .rfind("study,method,normals,function,norm,order,order_low,order_high,interval,h_min,h_max", 0) == 0);
  const std::vector<StudyRow> first = read_results_csv(dir + "/results.csv");
  CHECK(first.size() == 2 * 2 * 2);
  CHECK(out.find("order backward fem true x2 L2") != std::string::npos);
  // The same folder again: refused without --resume; with it nothing is recomputed, and a new h
  // adds only its own rows.
  CHECK(test::run_cli(args, &out, &err) == 1);
  CHECK(err.find("--resume") != std::string::npos);
  REQUIRE(test::run_cli(args + " --resume", &out, &err) == 0);
  CHECK(err.find("8 unit(s) already computed") != std::string::npos);
  CHECK(read_results_csv(dir + "/results.csv").size() == first.size());
  const std::string grown =
      "study backward --methods fem,interpolated --h 0.4,0.3,0.25 --functions x2 --centers 2 "
      "--bbox -1.5 1.5 --no-plots --resume --out " +
      dir;
  REQUIRE(test::run_cli(grown, &out, &err) == 0);
  const std::vector<StudyRow> after = read_results_csv(dir + "/results.csv");
  CHECK(after.size() == first.size() + 4);  // h = 0.25: 2 methods x 2 centres x 1 function
  for (std::size_t i = 0; i < first.size(); ++i) CHECK(after[i].error_l2 == first[i].error_l2);
  // A resume with another fixed option is refused naming it.
  CHECK(test::run_cli(args + " --resume --seed 5", &out, &err) == 1);
  CHECK(err.find("option 'seed' differs") != std::string::npos);
  // The eigen study's values are those of `corrlap eigs` for the same input (shift-invert, cholmod).
  const std::string eig_dir = dir + "_eigen";
  std::filesystem::remove_all(eig_dir);
  REQUIRE(test::run_cli("study eigen --methods fem --h 0.2 -k 10 --no-plots --out " + eig_dir, &out, &err) == 0);
  const std::vector<EigenRow> study_values = read_eigen_csv(eig_dir + "/eigen.csv");
  REQUIRE(study_values.size() == 10);
  const std::string eigs_file = eig_dir + "/eigs.txt";
  REQUIRE(test::run_cli("eigs --method fem --shape sphere1 --h 0.2 --bbox -2 2 --normals true -k 10 --solver cholmod "
                        "--out " +
                            eigs_file,
                        &out, &err) == 0);
  const Eigen::VectorXd eigs_values = read_scalars(eigs_file);
  REQUIRE(eigs_values.size() == 10);
  for (int i = 0; i < 10; ++i)
    CHECK(std::abs(study_values[std::size_t(i)].computed - eigs_values[i]) <= 1e-9 * (1.0 + eigs_values[i]));
  // Bad options through the CLI.
  const std::string d2 = " --no-plots --out " + dir + "_bad";
  CHECK(test::run_cli("study sideways" + d2, &out, &err) == 1);
  CHECK(err.find("unknown study 'sideways'") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem,nosuch --h 0.4" + d2, &out, &err) == 1);
  CHECK(err.find("nosuch") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --functions x9 --h 0.4" + d2, &out, &err) == 1);
  CHECK(err.find("x9") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --h 0,0.1" + d2, &out, &err) == 1);
  CHECK(err.find("must be positive") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --h ," + d2, &out, &err) == 1);
  CHECK(err.find("empty") != std::string::npos);
  CHECK(test::run_cli("study cotan --methods fem" + d2, &out, &err) == 1);
  CHECK(err.find("no mesh given (--mesh-file)") != std::string::npos);
  CHECK(test::run_cli("study cotan --mesh-file " + icosahedron_obj() + " --resolutions 64,x" + d2, &out, &err) == 1);
  CHECK(err.find("'x' is not an integer") != std::string::npos);
  CHECK(test::run_cli("study cotan --mesh-file " + icosahedron_obj() + " --normals true" + d2, &out, &err) == 1);
  CHECK(err.find("expected mesh (the reference's) or ii") != std::string::npos);
}
#endif
