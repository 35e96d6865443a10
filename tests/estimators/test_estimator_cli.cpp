// CLI: corrlap normals / corrlap curvature, including bad input (clear errors, exit code 1).
#include <doctest/doctest.h>

#include <cmath>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <corrlap/surface/implicit_shape.hpp>

#include "test_support.hpp"

using namespace corrlap;
using test::run_cli;

TEST_CASE("cli normals --normals ii reproduces the reference II normals (alpha 1/3)") {
  const std::string out = test::tmp_path("est_ii_h02.txt");
  std::string err;
  REQUIRE(
      run_cli("normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals ii --ii-alpha 0.3333333333333333 --out " + out,
              nullptr, &err) == 0);
  const Eigen::MatrixX3d n = read_normals(out);
  const Eigen::MatrixX3d ref = read_normals(test::reference_dir() + "/sphere1_h0.2/face_normals_ii.txt");
  REQUIRE(n.rows() == ref.rows());
  CHECK((n - ref).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("cli normals --normals true and --at vertices match the reference true normals") {
  const std::string dir = test::reference_dir() + "/sphere1_h0.2/";
  const std::string f = test::tmp_path("est_true_f.txt"), v = test::tmp_path("est_true_v.txt");
  REQUIRE(run_cli("normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals true --out " + f) == 0);
  REQUIRE(run_cli("normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals true --at vertices --out " + v) == 0);
  CHECK((read_normals(f) - read_normals(dir + "face_normals_true.txt")).cwiseAbs().maxCoeff() < 1e-14);
  CHECK((read_normals(v) - read_normals(dir + "vertex_normals_true.txt")).cwiseAbs().maxCoeff() < 1e-14);
}

TEST_CASE("cli curvature on the reference mesh reproduces mean_curvature_icnc and ccnc") {
  const std::string dir = test::reference_dir() + "/sphere1_h0.2/";
  const std::string out = test::tmp_path("est_curv_icnc");
  REQUIRE(run_cli("curvature --mesh " + dir + "mesh.obj --vertex-normals " + dir +
                  "vertex_normals_true.txt --radius 0.1 --out " + out) == 0);
  CHECK((read_scalars(out + "/H_faces.txt") - read_scalars(dir + "mean_curvature_icnc.txt")).cwiseAbs().maxCoeff() <
        1e-12);
  CHECK(read_scalars(out + "/H_vertices.txt").size() == 440);
  CHECK(read_normals(out + "/d1_faces.txt").rows() == 438);
  const std::string out2 = test::tmp_path("est_curv_ccnc");
  REQUIRE(run_cli("curvature --mesh " + dir + "mesh.obj --face-normals " + dir +
                  "face_normals_true.txt --radius 0.4472135954999579 --out " + out2) == 0);
  CHECK((read_scalars(out2 + "/H_faces.txt") - read_scalars(dir + "mean_curvature_ccnc_rsqrth.txt"))
            .cwiseAbs()
            .maxCoeff() < 1e-12);
}

TEST_CASE("cli curvature from a shape with ii normals gives H near 1 on sphere1") {
  const std::string out = test::tmp_path("est_curv_ii");
  REQUIRE(run_cli("curvature --shape sphere1 --h 0.05 --bbox -1.5 1.5 --normals ii --radius 0.2 --out " + out) == 0);
  const Eigen::VectorXd H = read_scalars(out + "/H_faces.txt");
  CHECK(std::abs(H.mean() - 1.0) < 0.02);
}

TEST_CASE("cli estimators reject bad input with clear errors") {
  const std::string dir = test::reference_dir() + "/sphere1_h0.2/";
  std::string err;
  CHECK(run_cli("normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 --radius 0.01 --out " + test::tmp_path("x.txt"),
                nullptr, &err) == 1);
  CHECK(err.find("smaller than one voxel") != std::string::npos);
  CHECK(run_cli("normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 --radius 500 --out " + test::tmp_path("x.txt"),
                nullptr, &err) == 1);
  CHECK(err.find("larger than the volume") != std::string::npos);
  // empty volume: the shape lies outside the box
  CHECK(run_cli("normals --shape sphere1 --center 50 0 0 --h 0.2 --bbox -1.5 1.5 --out " + test::tmp_path("x.txt"),
                nullptr, &err) == 1);
  CHECK(err.find("empty") != std::string::npos);
  CHECK(run_cli("curvature --mesh " + dir + "mesh.obj --vertex-normals " + dir + "face_normals_true.txt --out " +
                    test::tmp_path("c"),
                nullptr, &err) == 1);
  CHECK(err.find("expected 440") != std::string::npos);
  CHECK(err.find("face_normals_true.txt") != std::string::npos);
  CHECK(run_cli("curvature --mesh " + dir + "mesh.obj --vertex-normals " + dir +
                    "vertex_normals_true.txt --radius 1000 --out " + test::tmp_path("c"),
                nullptr, &err) == 1);
  CHECK(err.find("larger than the mesh") != std::string::npos);
  CHECK(run_cli("normals --mesh " + dir + "mesh.obj --normals ii --out " + test::tmp_path("x.txt"), nullptr, &err) ==
        1);
  CHECK(err.find("need voxels") != std::string::npos);
  CHECK(err.find("(--normals)") != std::string::npos);  // the library's parameter, in CLI terms
}

TEST_CASE("cli normals on a volume file gives the reference II normals, empty volumes are rejected") {
  DigitizationParams p;
  p.h = 0.2;
  p.min_aabb = -1.5;
  p.max_aabb = 1.5;
  const std::string vol = test::tmp_path("est_sphere_h02.vol");
  write_volume(vol, voxels_to_volume(digitize(make_implicit_shape("sphere1"), p)));
  const std::string out = test::tmp_path("est_ii_vol.txt");
  std::string err;
  REQUIRE(run_cli("normals --volume " + vol +
                      " --h 0.2 --normals ii --ii-radius 3 --ii-alpha 0.3333333333333333 --ii-thin-parts keep --out " +
                      out,
                  nullptr, &err) == 0);
  const Eigen::MatrixX3d n = read_normals(out);
  const Eigen::MatrixX3d ref = read_normals(test::reference_dir() + "/sphere1_h0.2/face_normals_ii.txt");
  REQUIRE(n.rows() == ref.rows());  // translation keeps the face order (docs/math.md §1.4 sort key)
  CHECK((n - ref).cwiseAbs().maxCoeff() < 1e-12);
  Volume empty;
  empty.size = Eigen::Vector3i(8, 8, 8);
  empty.values.assign(512, 0);
  const std::string evol = test::tmp_path("est_empty.vol");
  write_volume(evol, empty);
  CHECK(run_cli("normals --volume " + evol + " --out " + test::tmp_path("x.txt"), nullptr, &err) == 1);
  CHECK(err.find("empty") != std::string::npos);
  CHECK(run_cli("curvature --volume " + evol + " --out " + test::tmp_path("c_empty"), nullptr, &err) == 1);
  CHECK(err.find("empty") != std::string::npos);
}

TEST_CASE("cli normals: the old --estimator/--radius/--alpha still work, with a deprecation note") {
  const std::string shape = "normals --shape sphere1 --h 0.2 --bbox -1.5 1.5 ";
  const std::string now = test::tmp_path("est_spelling_new.txt"), old = test::tmp_path("est_spelling_old.txt");
  std::string err_new, err_old;
  REQUIRE(run_cli(shape + "--normals ii --ii-radius 2.5 --ii-alpha 0.3 --at vertices --out " + now, nullptr,
                  &err_new) == 0);
  REQUIRE(run_cli(shape + "--estimator ii --radius 2.5 --alpha 0.3 --at vertices --out " + old, nullptr, &err_old) ==
          0);
  CHECK(test::read_text(now) == test::read_text(old));  // the same normals, bit for bit
  // ... and not those of the default radius: the aliases reach the II parameters.
  const std::string plain = test::tmp_path("est_spelling_default.txt");
  REQUIRE(run_cli(shape + "--normals ii --at vertices --out " + plain) == 0);
  CHECK(test::read_text(now) != test::read_text(plain));
  CHECK(err_new.find("deprecated") == std::string::npos);
  CHECK(err_old.find("--estimator is deprecated; use --normals") != std::string::npos);
  CHECK(err_old.find("--radius is deprecated; use --ii-radius") != std::string::npos);
  CHECK(err_old.find("--alpha is deprecated; use --ii-alpha") != std::string::npos);
  // The old spellings are hidden from the help, the new ones listed.
  std::string help;
  REQUIRE(run_cli("normals --help", &help) == 0);
  CHECK(help.find("--ii-radius") != std::string::npos);
  CHECK(help.find("--estimator") == std::string::npos);
}

TEST_CASE("cli curvature takes the shared normal options (--ii-radius, --ii-alpha reach the II normals)") {
  const std::string shape = "curvature --shape sphere1 --h 0.2 --bbox -1.5 1.5 --normals ii --radius 0.5 ";
  const std::string a = test::tmp_path("est_curv_ii_a"), b = test::tmp_path("est_curv_ii_b");
  REQUIRE(run_cli(shape + "--out " + a) == 0);
  REQUIRE(run_cli(shape + "--ii-radius 2 --ii-alpha 0.3 --out " + b) == 0);
  CHECK(test::read_text(a + "/H_vertices.txt") != test::read_text(b + "/H_vertices.txt"));
  std::string err;
  CHECK(run_cli("curvature --mesh " + test::reference_dir() + "/sphere1_h0.2/mesh.obj --vertex-normals " +
                    test::reference_dir() + "/sphere1_h0.2/vertex_normals_true.txt --normals ii --out " + a,
                nullptr, &err) == 1);
  CHECK(err.find("--normals applies to --shape/--volume") != std::string::npos);
}
