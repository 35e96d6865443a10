// `corrlap operators` reproduces the reference matrices; `corrlap eigs` the spectra of docs/math.md §12.3.
#include <doctest/doctest.h>

#include <corrlap/io/text_io.hpp>
#include <sstream>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

#ifdef CORRLAP_CLI
TEST_CASE("corrlap operators writes L.mtx and M.mtx equal to the reference for the four quad methods") {
  const std::string common = " --mesh " + sphere_ref("mesh.obj") + " --face-normals " +
                             sphere_ref("face_normals_true.txt") + " --vertex-normals " +
                             sphere_ref("vertex_normals_true.txt");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"fem", "fem"}, {"interpolated", "icc"}, {"polydec", "poly"}, {"projected-polydec", "polyproj"}};
  for (const auto& [method, prefix] : cases) {
    const std::string out = tmp_path("ops_" + method);
    std::string err;
    REQUIRE(run_cli_tagged("t0", "operators --method " + method + common + " --out " + out, nullptr, &err) == 0);
    const auto method_copy = method;  // clang 14: no structured binding inside CAPTURE/INFO
    INFO(method_copy << ": " << err);
    for (const std::string m : {"L", "M"}) {
      const MatrixDiff d = compare_matrices(read_matrix_market(out + "/" + m + ".mtx"),
                                            read_matrix_market(sphere_ref(prefix + "_" + m + "0.mtx")));
      CHECK(d.relative <= 1e-12);
      CHECK(d.pattern_mismatch == 0);
    }
  }
}

TEST_CASE("corrlap operators --shape --normals true reproduces the reference mesh and normals path") {
  const std::string out = tmp_path("ops_shape_icc");
  REQUIRE(run_cli_tagged(
              "t1", "operators --method interpolated --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals true --out " +
                        out) == 0);
  const MatrixDiff d =
      compare_matrices(read_matrix_market(out + "/L.mtx"), read_matrix_market(sphere_ref("icc_L0.mtx")));
  CHECK(d.relative <= 1e-12);
  CHECK(d.pattern_mismatch == 0);
  const std::string all = tmp_path("ops_all");
  REQUIRE(run_cli_tagged("t1", "operators --method polydec --shape sphere1 --h 0.5 --all --out " + all) == 0);
  for (const std::string f : {"D0", "sharp", "flat", "M1", "M_lumped"})
    CHECK(read_matrix_market(all + "/" + f + ".mtx").rows() > 0);
}

TEST_CASE("corrlap operators passes --mass, --assembly, --lambda and --param to the method") {
  const std::string a = tmp_path("ops_lumped"), b = tmp_path("ops_local"), c = tmp_path("ops_param");
  REQUIRE(run_cli_tagged(
              "t2", "operators --method fem --shape sphere1 --h 0.5 --normals true --mass lumped --out " + a) == 0);
  CHECK(read_matrix_market(a + "/M.mtx").nonZeros() == 80);  // 80 vertices at h = 0.5: diagonal
  REQUIRE(run_cli_tagged("t2",
                         "operators --method interpolated --shape sphere1 --h 0.5 --normals true --assembly local "
                         "--lambda 0.2 --out " +
                             b) == 0);
  REQUIRE(run_cli_tagged("t2",
                         "operators --method interpolated --shape sphere1 --h 0.5 --normals true --param "
                         "assembly=local --param lambda=0.2 --out " +
                             c) == 0);
  const Eigen::SparseMatrix<double> Lb = read_matrix_market(b + "/L.mtx"), Lc = read_matrix_market(c + "/L.mtx");
  CHECK(compare_matrices(Lb, Lc).relative == 0.0);
  CHECK(Lb.nonZeros() == read_matrix_market(a + "/L.mtx").nonZeros());  // local variant: FEM's 9-point pattern
}

TEST_CASE("corrlap operators passes --t, --cutoff and --mass to the heat kernel") {
  const std::string a = tmp_path("ops_heat_flags"), b = tmp_path("ops_heat_param"), c = tmp_path("ops_heat_default");
  REQUIRE(
      run_cli_tagged(
          "t4", "operators --method heat-kernel --shape sphere1 --h 0.2 --t 0.02 --cutoff 2 --mass identity --out " +
                    a) == 0);
  REQUIRE(run_cli_tagged("t4",
                         "operators --method heat-kernel --shape sphere1 --h 0.2 --param t=0.02 --param cutoff=2 "
                         "--param mass=identity --out " +
                             b) == 0);
  REQUIRE(run_cli_tagged("t4", "operators --method heat-kernel --shape sphere1 --h 0.2 --out " + c) == 0);
  const Eigen::SparseMatrix<double> La = read_matrix_market(a + "/L.mtx"), Lb = read_matrix_market(b + "/L.mtx");
  CHECK(compare_matrices(La, Lb).relative == 0.0);
  CHECK(La.nonZeros() < read_matrix_market(c + "/L.mtx").nonZeros());  // smaller t and cut-off: fewer pairs
  const Eigen::SparseMatrix<double> Ma = read_matrix_market(a + "/M.mtx");
  CHECK(Ma.nonZeros() == Ma.rows());
  CHECK(Eigen::VectorXd(Ma.diagonal()).isOnes());  // mass=identity
}

TEST_CASE("corrlap operators reports bad input with exit code 1 and a message") {
  std::string err;
  CHECK(run_cli_tagged("t3", "operators --method fem --mesh " + sphere_ref("mesh.obj") + " --out " + tmp_path("x"),
                       nullptr, &err) == 1);
  CHECK(err.find("face normals") != std::string::npos);
  CHECK(run_cli_tagged("t3", "operators --method fem --shape sphere1 --h 0.5 --kappa 1 --out " + tmp_path("x"), nullptr,
                       &err) == 1);
  CHECK(err.find("kappa") != std::string::npos);
  CHECK(run_cli_tagged("t3", "operators --method nope --shape sphere1 --h 0.5 --out " + tmp_path("x"), nullptr, &err) ==
        1);
  CHECK(err.find("fem") != std::string::npos);  // lists the valid names
  CHECK(run_cli_tagged("t3",
                       "operators --method interpolated --mesh " + sphere_ref("mesh.obj") + " --vertex-normals " +
                           sphere_ref("face_normals_true.txt") + " --out " + tmp_path("x"),
                       nullptr, &err) == 1);
  CHECK(err.find("vertex normals") != std::string::npos);
}

TEST_CASE("corrlap eigs reproduces the h=0.1 eigenvalues of docs/math.md §12.3") {
  // Radial face normals; the CLI builds vertex normals from them (docs/math.md §1.5), so test fem and
  // projected-polydec, which use face normals only.
  const std::string out = tmp_path("eigs_fem.txt");
  REQUIRE(run_cli_tagged(
              "t4", "eigs --method fem --shape sphere1 --h 0.1 --bbox -2 2 --normals true -k 16 --out " + out) == 0);
  const Eigen::VectorXd values = read_scalars(out);  // after its "# ..." line of units
  const std::vector<double> mu(values.data(), values.data() + values.size());
  REQUIRE(mu.size() == 16);
  CHECK(std::abs(mu[0]) <= 1e-9);
  const double expected[15] = {2.0177,  2.0177,  2.0177,  6.04467, 6.04467, 6.04467, 6.09828, 6.09828,
                               12.0573, 12.1728, 12.1728, 12.1728, 12.2069, 12.2069, 12.2069};
  for (int i = 0; i < 15; ++i) CHECK(mu[std::size_t(i) + 1] == doctest::Approx(expected[i]).epsilon(1e-4));
  std::string stdout_text;
  REQUIRE(run_cli_tagged("t4",
                         "eigs --method projected-polydec --shape sphere1 --h 0.25 --bbox -2 2 --normals true -k 2",
                         &stdout_text) == 0);
  std::istringstream in2(stdout_text);
  double a, b;
  in2 >> a >> b;
  CHECK(b == doctest::Approx(2.0609).epsilon(2e-5));
  std::string err;
  // Unknown eigen/linear solver options are refused with the list of valid keys.
  CHECK(run_cli_tagged(
            "t4",
            "eigs --method fem --shape sphere1 --h 0.1 --normals true --solver cholmod --solver-option nosuchkey=1",
            nullptr, &err) == 1);
  CHECK(err.find("nosuchkey") != std::string::npos);
}
#endif
