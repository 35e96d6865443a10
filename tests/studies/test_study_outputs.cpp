// What `corrlap study` writes and refuses (docs/studies.md, "Undefined values", "Options given twice"):
// undefined values are empty fields, never nan; orders with too few points are empty with a warning;
// repeated values, shapes without a reference, naive with diffusion and open cotan meshes are named
// errors, in the library and through the CLI's flags.
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/studies/cotan_reference.hpp>
#include <corrlap/studies/regularization_study.hpp>
#include <corrlap/studies/study.hpp>
#include <corrlap/studies/study_tables.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "surface/icosahedron.hpp"
#include "test_support.hpp"

using namespace corrlap;

namespace {

// The icosahedron as an OBJ file, without its last `drop` triangles (an open mesh when drop > 0).
std::string icosahedron_obj(const std::string& name, int drop) {
  const std::string path = test::tmp_path(name);
  const TriangleMesh ico = test::icosahedron();
  PolygonMesh m;
  m.positions = ico.positions;
  for (Eigen::Index f = 0; f + drop < ico.triangles.rows(); ++f)
    m.faces.push_back({ico.triangles(f, 0), ico.triangles(f, 1), ico.triangles(f, 2)});
  write_mesh(path, m);
  return path;
}

StudyOptions small(StudyKind kind) {
  StudyOptions o;
  o.kind = kind;
  o.methods = {"fem"};
  o.h = {0.4, 0.3};
  o.functions = {"x2"};
  o.min_aabb = -1.5;
  o.max_aabb = 1.5;
  return o;
}

// `what` of the InputError that `f` throws, and its parameter.
template <class F>
std::pair<std::string, std::string> input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return {e.what(), e.parameter()};
  }
  return {"(no error)", ""};
}

// "nan", "inf" or "infinity" as a token (not inside a word), any case.
bool has_non_finite_token(const std::string& text) {
  static const std::regex token("(^|[^A-Za-z_])(nan|inf|infinity)([^A-Za-z_]|$)", std::regex::icase);
  return std::regex_search(text, token);
}

}  // namespace

TEST_CASE("study tables: undefined values are empty fields, read back as NaN, required fields are checked") {
  // One grid step: no order; two rows at two h: an order without interval.
  std::vector<StudyRow> rows;
  for (double h : {0.2, 0.1}) {
    StudyRow r{.study = "backward", .method = "fem", .normals = "true", .function = "x2", .h = h, .center = 0};
    r.error_linf = 2 * h * h;
    r.error_l2 = h * h;
    rows.push_back(r);
  }
  StudyRow lone{.study = "backward", .method = "fem", .normals = "true", .function = "expx", .h = 0.1, .center = 0};
  lone.error_linf = lone.error_l2 = 0.01;
  rows.push_back(lone);
  const std::vector<OrderRow> orders = fit_orders(rows);
  REQUIRE(orders.size() == 4);  // every group and norm has a row
  CHECK(orders[1].order == doctest::Approx(2.0));
  CHECK(std::isnan(orders[1].low));
  CHECK(std::isnan(orders[3].order));
  CHECK(orders[3].points == 1);
  const std::vector<std::string> shortfalls = order_shortfalls(orders);
  REQUIRE(shortfalls.size() == 2);
  CHECK(shortfalls[0].find("2 order(s) left empty (e.g. backward fem true expx Linf, 1 row(s))") == 0);
  CHECK(shortfalls[0].find("two grid steps") != std::string::npos);
  CHECK(shortfalls[1].find("2 interval(s) left empty") == 0);
  CHECK(shortfalls[1].find("three rows") != std::string::npos);

  const std::string orders_csv = test::tmp_path("orders_empty_fields.csv");
  write_orders_csv(orders_csv, orders);
  const std::string text = test::read_text(orders_csv);
  CHECK_FALSE(has_non_finite_token(text));
  // The lone group's L2 row: order, interval, h_min and h_max all empty (no zero stands in for them).
  CHECK(text.find("backward,fem,true,expx,l2,,,,95% t-interval of the least-squares slope over every "
                  "centre,0.10000000000000001,0.10000000000000001,1") != std::string::npos);

  // The eigen study's index 0: an empty relative error, read back as NaN.
  EigenRow zero{.method = "fem", .normals = "true", .h = 0.2, .center = 0, .index = 0};
  zero.computed = 1e-13;
  zero.relative_error = std::nan("");
  const std::string eigen_csv = test::tmp_path("eigen_empty_fields.csv");
  write_eigen_csv(eigen_csv, {zero}, false);
  const std::string eigen_text = test::read_text(eigen_csv);
  CHECK_FALSE(has_non_finite_token(eigen_text));
  CHECK(eigen_text.find(",1e-13,,") != std::string::npos);
  const std::vector<EigenRow> back = read_eigen_csv(eigen_csv);
  REQUIRE(back.size() == 1);
  CHECK(std::isnan(back[0].relative_error));
  CHECK(back[0].computed == 1e-13);

  // Results: an empty error is undefined, a nan of an older file too; an empty h is an error.
  const std::string results_csv = test::tmp_path("results_empty_fields.csv");
  write_results_csv(results_csv, {rows[0]}, false);
  {
    std::ofstream out(results_csv, std::ios::app);
    out << "backward,fem,true,x2,0.05,0,0,0,0,10,10,,nan,0.1\n";
  }
  const std::vector<StudyRow> read = read_results_csv(results_csv);
  REQUIRE(read.size() == 2);
  CHECK(std::isnan(read[1].error_linf));
  CHECK(std::isnan(read[1].error_l2));
  {
    std::ofstream out(results_csv, std::ios::app);
    out << "backward,fem,true,x2,,0,0,0,0,10,10,1,1,0.1\n";
  }
  CHECK_THROWS_WITH_AS(read_results_csv(results_csv), doctest::Contains("line 4, column 5: '' is not a number"),
                       IoError);
}

TEST_CASE("study options: values given twice are refused naming the parameter") {
  StudyOptions o = small(StudyKind::Backward);
  o.h = {0.1, 0.05, 0.1};
  auto [what, parameter] = input_error([&] { o.validate(); });
  CHECK(what == "study backward: grid step h = 0.1 is given twice; give each once");
  CHECK(parameter == "h");
  o.h = {0.1, 0.1 * (1 + 1e-14)};  // the same step up to rounding (as resume matches units)
  CHECK(input_error([&] { o.validate(); }).second == "h");
  o = small(StudyKind::Forward);
  o.methods = {"fem", "interpolated", "fem"};
  CHECK(input_error([&] { o.validate(); }).second == "methods");
  o = small(StudyKind::Forward);
  o.functions = {"x2", "x2"};
  CHECK(input_error([&] { o.validate(); }).second == "functions");
  o = small(StudyKind::Cotan);
  o.mesh_file = "any.obj";
  o.normals = "mesh";
  o.resolutions = {16, 32, 16};
  CHECK(input_error([&] { o.validate(); }).second == "resolutions");
  RegularizationStudyOptions r;
  r.h = {0.2, 0.2};
  CHECK(input_error([&] { r.validate(); }).second == "h");
  r = {};
  r.shapes = {"sphere1", "torus", "sphere1"};
  CHECK(input_error([&] { r.validate(); }).first ==
        "study regularization: shape sphere1 is given twice; give each once");
}

TEST_CASE("study options: only the unit sphere has a reference, shape does not apply to the cotan study") {
  for (StudyKind kind : {StudyKind::Forward, StudyKind::Backward, StudyKind::Eigen}) {
    StudyOptions o = small(kind);
    CAPTURE(to_string(kind));
    for (const char* shape : {"torus", "sphere9", "x^2+y^2+z^2-4"}) {
      o.shape = shape;
      auto [what, parameter] = input_error([&] { o.validate(); });
      CHECK(what.find("shape '" + std::string(shape) + "' has no reference solution") != std::string::npos);
      CHECK(what.find("use sphere1") != std::string::npos);
      CHECK(parameter == "shape");
    }
    o.shape = "x^2+y^2+z^2-1";  // the unit sphere by its polynomial
    CHECK_NOTHROW(o.validate());
  }
  StudyOptions c = small(StudyKind::Cotan);
  c.mesh_file = "any.obj";
  c.normals = "mesh";
  c.shape = "torus";
  CHECK(input_error([&] { c.validate(); }).second == "shape");
}

TEST_CASE("study options: naive and diffusion exclude each other, and belong to forward and cotan") {
  StudyOptions o = small(StudyKind::Forward);
  o.naive = true;
  CHECK(o.forward_diffusion() == 0.0);
  o.diffusion = 0.05;
  auto [what, parameter] = input_error([&] { o.validate(); });
  CHECK(what.find("naive and diffusion exclude each other") != std::string::npos);
  CHECK(parameter == "naive");
  o.naive = false;
  CHECK_NOTHROW(o.validate());
  CHECK(o.forward_diffusion() == 0.05);
  o.diffusion.reset();
  CHECK(o.forward_diffusion() == kDefaultStudyDiffusion);
  o.diffusion = -1.0;
  CHECK(input_error([&] { o.validate(); }).second == "diffusion");
  for (StudyKind kind : {StudyKind::Backward, StudyKind::Eigen}) {
    StudyOptions b = small(kind);
    b.naive = true;
    CHECK(input_error([&] { b.validate(); }).first.find("naive belongs to the forward and cotan studies") !=
          std::string::npos);
    b.naive = false;
    b.diffusion = 0.035;
    CHECK(input_error([&] { b.validate(); }).second == "diffusion");
  }
}

TEST_CASE("cotan study: a mesh that is not closed is refused before the subdivision") {
  const std::vector<const TestFunction*> x2 = {&test_function("x2")};
  // Without one triangle the icosahedron has a triangular hole: three boundary edges.
  const PolygonMesh open = read_mesh(icosahedron_obj("icosahedron_open.obj", 1));
  auto [what, parameter] = input_error([&] { (void)make_cotan_reference(open, x2, 100000); });
  CHECK(what.find("cotan study: the mesh is not closed: 3 boundary edge(s), 0 edge(s) with more than two") == 0);
  CHECK(what.find("close its holes") != std::string::npos);
  CHECK(parameter == "mesh_file");
  // A fan of triangles sharing one edge: non-manifold.
  PolygonMesh fan = read_mesh(icosahedron_obj("icosahedron_closed.obj", 0));
  fan.positions.conservativeResize(fan.positions.rows() + 1, 3);
  fan.positions.row(fan.positions.rows() - 1) = Eigen::RowVector3d(0, 0, 5);
  const int a = fan.faces[0][0], b = fan.faces[0][1];
  fan.faces.push_back({a, b, int(fan.positions.rows() - 1)});
  CHECK(input_error([&] { (void)make_cotan_reference(fan, x2, 0); }).first.find("1 edge(s) with more than two") !=
        std::string::npos);
}

#ifdef CORRLAP_CLI
TEST_CASE("corrlap study: refusals name the flag") {
  const std::string out_dir = " --no-plots --out " + test::tmp_path("study_refusals");
  std::string out, err;
  CHECK(test::run_cli("study backward --methods fem --h 0.1,0.1" + out_dir, &out, &err) == 1);
  CHECK(err.find("grid step h = 0.1 is given twice; give each once (--h)") != std::string::npos);
  CHECK(test::run_cli("study forward --methods fem --h 0.4 --naive --diffusion 0.05" + out_dir, &out, &err) == 1);
  CHECK(err.find("naive and diffusion exclude each other") != std::string::npos);
  CHECK(err.find("(--naive)") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --h 0.4 --naive" + out_dir, &out, &err) == 1);
  CHECK(err.find("study backward: --naive does not apply to this study (it belongs to forward and cotan studies)") !=
        std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --h 0.4 --shape torus" + out_dir, &out, &err) == 1);
  CHECK(err.find("shape 'torus' has no reference solution") != std::string::npos);
  CHECK(err.find("(--shape)") != std::string::npos);
  CHECK(test::run_cli("study cotan --methods fem --mesh-file " + icosahedron_obj("icosahedron_open.obj", 1) + out_dir,
                      &out, &err) == 1);
  CHECK(err.find("the mesh is not closed: 3 boundary edge(s)") != std::string::npos);
  CHECK(err.find("(--mesh-file)") != std::string::npos);
  CHECK(err.find("internal error") == std::string::npos);
  // An option of another kind of study is refused, not ignored.
  CHECK(test::run_cli("study cotan --methods fem --mesh-file " + icosahedron_obj("icosahedron_closed.obj", 0) +
                          " --h 0.1" + out_dir,
                      &out, &err) == 1);
  CHECK(err.find("study cotan: --h does not apply to this study (it belongs to forward, backward, eigen and "
                 "regularization studies)") != std::string::npos);
  CHECK(test::run_cli("study backward --methods fem --h 0.4 -k 5" + out_dir, &out, &err) == 1);
  CHECK(err.find("study backward: -k does not apply to this study (it belongs to eigen study)") != std::string::npos);
  CHECK(test::run_cli("study regularization --shape torus" + out_dir, &out, &err) == 1);
  CHECK(err.find("study regularization: --shape does not apply") != std::string::npos);
  CHECK(test::run_cli("study eigen --methods fem --h 0.4 --shapes torus" + out_dir, &out, &err) == 1);
  CHECK(err.find("study eigen: --shapes does not apply") != std::string::npos);
}

TEST_CASE("corrlap study --resume with a new function adds its rows only, once per unit") {
  const std::string dir = test::tmp_path("study_resume_function");
  std::filesystem::remove_all(dir);
  const std::string args = "study backward --methods fem --h 0.4,0.3 --bbox -1.5 1.5 --no-plots --out " + dir;
  std::string out, err;
  REQUIRE(test::run_cli(args + " --functions x2", &out, &err) == 0);
  REQUIRE(test::run_cli(args + " --functions x2,expx --resume", &out, &err) == 0);
  const std::vector<StudyRow> rows = read_results_csv(dir + "/results.csv");
  CHECK(rows.size() == 4);  // 2 h x (x2, expx), the x2 rows not repeated
  for (const SummaryRow& s : summarize(rows)) CHECK(s.centers == 1);
}

TEST_CASE("corrlap study: no file of any study kind holds nan or inf, every JSON parses") {
  const std::string mesh = icosahedron_obj("icosahedron_closed.obj", 0);
  const std::string common = " --methods fem --no-plots --out ";
  struct Run {
    std::string name, args, warning;  // warning: expected on stderr ("" for none)
  };
  // The cases that wrote nan: eigen index 0; two grid steps with one centre (no interval); one grid
  // step (no order); the cotan study with two resolutions.
  const std::vector<Run> runs = {
      {"eigen", "study eigen --h 0.4 -k 6 --bbox -1.5 1.5", ""},
      {"forward", "study forward --h 0.4,0.3 --functions x2,p6 --bbox -1.5 1.5", "interval(s) left empty"},
      {"backward", "study backward --h 0.3 --functions x2 --bbox -1.5 1.5", "order(s) left empty"},
      {"cotan", "study cotan --mesh-file " + mesh + " --resolutions 8,12 --refine-vertices 100 --functions x2",
       "interval(s) left empty"},
      {"regularization", "study regularization --shapes sphere1 --h 0.3 --bbox -1.5 1.5", ""},
  };
  for (const Run& run : runs) {
    CAPTURE(run.name);
    const std::string dir = test::tmp_path("study_finite_" + run.name);
    std::filesystem::remove_all(dir);
    std::string out, err;
    REQUIRE(test::run_cli(run.args + common + dir, &out, &err) == 0);
    if (run.warning.empty())
      CHECK(err.find("warning") == std::string::npos);
    else
      CHECK(err.find("warning: study: " + dir + "/orders.csv: ") != std::string::npos);
    CHECK(err.find(run.warning) != std::string::npos);
    int files = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
      if (!entry.is_regular_file()) continue;
      ++files;
      const std::string path = entry.path().string(), text = test::read_text(path);
      CAPTURE(path);
      CHECK_FALSE(has_non_finite_token(text));
      if (entry.path().extension() == ".json") CHECK_FALSE(nlohmann::json::parse(text, nullptr, false).is_discarded());
    }
    CHECK(files >= 1);
  }
  CHECK(has_non_finite_token("a,NaN,b"));  // the scan sees what it looks for
  CHECK(has_non_finite_token("[-inf]"));
  CHECK_FALSE(has_non_finite_token("interpolated,refine_vertices,information"));
}
#endif
