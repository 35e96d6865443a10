// The coordinates of the outputs (docs/io.md, "Anatomical spaces" and "Coordinates"): one
// segmentation saved by 3D Slicer as an LPS .nrrd and as a RAS .nii.gz gives outputs that differ by
// the x/y flip in their own spaces and agree after --output-space; curvature, normals, solve and
// eigs follow --output-units like digitize and regularize.
#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <corrlap/io/mesh_io.hpp>
#include <corrlap/io/text_io.hpp>
#include <corrlap/io/volume_io.hpp>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "test_support.hpp"

#ifdef CORRLAP_CLI

namespace {

using corrlap::test::read_text;
using corrlap::test::run_cli;
using corrlap::test::tmp_path;
using namespace corrlap;

std::string scratch(const std::string& name) { return tmp_path("space_" + std::to_string(::getpid()) + "_" + name); }

// A ball of label 1, radius 4.5 voxels, in 14^3 voxels of 0.5 mm, placed in LPS with its axes
// permuted and flipped (every number exact in float32, so that NIfTI holds it exactly).
VolumeData ball_segmentation() {
  VolumeData v;
  v.size = Eigen::Vector3i(14, 14, 14);
  v.type = VoxelValueType::UInt8;
  v.bytes.assign(14 * 14 * 14, 0);
  for (int k = 0; k < 14; ++k)
    for (int j = 0; j < 14; ++j)
      for (int i = 0; i < 14; ++i)
        if (Eigen::Vector3d(i - 6.5, j - 6.0, k - 6.5).norm() <= 4.5) v.bytes[std::size_t((k * 14 + j) * 14 + i)] = 1;
  v.geometry.spacing = Eigen::Vector3d::Constant(0.5);
  v.geometry.direction << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // i along +y, j along -x
  v.geometry.origin = Eigen::Vector3d(12.25, -30.5, 8.0);
  v.geometry.space = PhysicalSpace::LPS;
  return v;
}

Eigen::MatrixX3d digitized(const std::string& volume, const std::string& flags, std::string* obj_text = nullptr) {
  const std::string out = scratch("d.obj");
  std::string err;
  INFO(flags);
  REQUIRE(run_cli("digitize --volume " + volume + " --out " + out + flags, nullptr, &err) == 0);
  if (obj_text) *obj_text = read_text(out);
  return read_mesh(out).positions;
}

double max_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  REQUIRE(a.rows() == b.rows());
  REQUIRE(a.cols() == b.cols());
  return (a - b).cwiseAbs().maxCoeff();
}

std::vector<double> numbers(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> v;
  double x = 0;
  while (in >> x) v.push_back(x);
  return v;
}

}  // namespace

TEST_CASE("One segmentation as LPS .nrrd and RAS .nii.gz: outputs differ by the x/y flip, agree with --output-space") {
  const VolumeData seg = ball_segmentation();
  const std::string nrrd = scratch("seg.nrrd"), nifti = scratch("seg.nii.gz");
  write_volume_data(nrrd, seg);
  write_volume_data(nifti, seg);  // NIfTI's writer flips the geometry into RAS
  std::string nrrd_obj, nifti_obj;
  const Eigen::MatrixX3d lps = digitized(nrrd, "", &nrrd_obj), ras = digitized(nifti, "", &nifti_obj);
  // In their own spaces: the same vertices, x and y flipped (exact: every number is exact in float32).
  CHECK(max_difference(lps * Eigen::Vector3d(-1, -1, 1).asDiagonal(), ras) == 0.0);
  CHECK(lps.col(0).maxCoeff() > 0.0);  // not a mesh that the flip maps to itself by chance
  // Each file names its space for 3D Slicer.
  CHECK(nrrd_obj.find("\n# SPACE=LPS\n") != std::string::npos);
  CHECK(nifti_obj.find("\n# SPACE=RAS\n") != std::string::npos);
  // --output-space: the same coordinates from either file.
  for (const char* space : {"ras", "lps", "RAS"}) {
    CAPTURE(space);
    const std::string flag = std::string(" --output-space ") + space;
    const Eigen::MatrixX3d& expected = space[0] == 'l' ? lps : ras;
    CHECK(max_difference(digitized(nrrd, flag), expected) == 0.0);
    CHECK(max_difference(digitized(nifti, flag), expected) == 0.0);
  }
  // A flip of two axes is a rotation: the faces keep their order (a mirror would reverse them).
  const std::string a = scratch("a.obj"), b = scratch("b.obj");
  REQUIRE(run_cli("digitize --volume " + nrrd + " --out " + a, nullptr, nullptr) == 0);
  REQUIRE(run_cli("digitize --volume " + nifti + " --out " + b, nullptr, nullptr) == 0);
  const PolygonMesh fa = read_mesh(a), fb = read_mesh(b);
  REQUIRE(fa.faces.size() == fb.faces.size());
  bool same_faces = true;
  for (std::size_t f = 0; f < fa.faces.size(); ++f)
    same_faces = same_faces && std::equal(fa.faces[f].begin(), fa.faces[f].end(), fb.faces[f].begin());
  CHECK(same_faces);

  // regularize names the space of its outputs in metrics.json and in the meshes.
  const std::string dir = scratch("reg");
  std::string err;
  REQUIRE(run_cli("regularize --volume " + nrrd + " --output-space ras --no-render --out " + dir, nullptr, &err) == 0);
  std::ifstream metrics(dir + "/metrics.json");
  const nlohmann::json m = nlohmann::json::parse(metrics);
  CHECK(m["output_space"] == "RAS");
  CHECK(m["output_units"] == "physical");
  CHECK(read_text(dir + "/regularized.obj").find("\n# SPACE=RAS\n") != std::string::npos);
  CHECK(read_text(dir + "/regularized.ply").find("\ncomment SPACE=RAS\n") != std::string::npos);
}

TEST_CASE("Output spaces need physical units and an input whose space is known") {
  VolumeData plain = ball_segmentation();
  plain.geometry = VolumeGeometry{};
  const std::string vol = scratch("plain.nrrd");
  write_volume_data(vol, plain);  // "space dimension: 3": no anatomy
  const std::string out = scratch("x.obj");
  std::string err;
  CHECK(run_cli("digitize --volume " + vol + " --output-space ras --out " + out, nullptr, &err) == 1);
  CHECK(err.find("--output-space ras: the input's physical space is unknown") != std::string::npos);
  CHECK(err.find("omit --output-space") != std::string::npos);
  CHECK(run_cli("digitize --shape sphere1 --h 0.5 --output-space lps --out " + out, nullptr, &err) == 1);
  CHECK(err.find("shapes, mesh files and arrays have no anatomical space") != std::string::npos);
  write_volume_data(scratch("seg.nrrd"), ball_segmentation());
  CHECK(run_cli("digitize --volume " + scratch("seg.nrrd") + " --output-units world --output-space ras --out " + out,
                nullptr, &err) == 1);
  CHECK(err.find("applies to --output-units physical") != std::string::npos);
  // The default writes the file's own space, named or not.
  REQUIRE(run_cli("digitize --volume " + vol + " --out " + out, nullptr, &err) == 0);
  CHECK(read_text(out).find("SPACE=") == std::string::npos);
}

TEST_CASE("curvature, normals, solve and eigs follow --output-units: lengths in mm, curvatures in 1/mm") {
  const VolumeData seg = ball_segmentation();
  const std::string vol = scratch("units.nrrd");
  write_volume_data(vol, seg);
  const double mm = 0.5;  // the voxel side
  const std::string in = " --volume " + vol;
  std::string err;

  // curvature: H, k1, k2 in 1 / length, G in 1 / length^2; a ball of radius ~2.25 mm has H ~ 1/2.25 per mm.
  const std::string cv = scratch("cv"), cp = scratch("cp");
  REQUIRE(run_cli("curvature" + in + " --radius 0.5 --output-units voxels --out " + cv, nullptr, &err) == 0);
  REQUIRE(run_cli("curvature" + in + " --radius 0.5 --out " + cp, nullptr, &err) == 0);
  for (const char* name : {"H", "k1", "k2", "G"}) {
    CAPTURE(name);
    const double power = std::string(name) == "G" ? 2.0 : 1.0;
    const Eigen::VectorXd v = read_scalars(cv + "/" + name + "_faces.txt"),
                          p = read_scalars(cp + "/" + name + "_faces.txt");
    CHECK(max_difference(p, v / std::pow(mm, power)) < 1e-9 * v.cwiseAbs().maxCoeff() / std::pow(mm, power));
  }
  // Each file says what it holds and in which units.
  CHECK(read_text(cp + "/H_faces.txt")
            .rfind("# H: mean curvature at faces in 1/length of physical units (SPACE=LPS)\n", 0) == 0);
  CHECK(read_text(cv + "/G_vertices.txt")
            .rfind("# G: Gaussian curvature at vertices in 1/length^2 of voxels units\n", 0) == 0);
  const double mean_h = read_scalars(cp + "/H_faces.txt").mean();
  CHECK(std::abs(mean_h) == doctest::Approx(1.0 / (4.5 * mm)).epsilon(0.25));
  CHECK(read_text(cp + "/curvature.ply").find("comment SPACE=LPS") != std::string::npos);
  // The principal directions turn with the voxel axes (i along +y, j along -x).
  const Eigen::MatrixX3d dv = read_normals(cv + "/d1_faces.txt"), dp = read_normals(cp + "/d1_faces.txt");
  CHECK(max_difference(dp, dv * seg.geometry.direction.transpose()) < 1e-12);

  // normals: unit vectors turned with the voxel axes, and by the space's flip.
  const std::string nv = scratch("nv.txt"), np = scratch("np.txt"), nr = scratch("nr.txt");
  REQUIRE(run_cli("normals" + in + " --output-units voxels --out " + nv, nullptr, &err) == 0);
  REQUIRE(run_cli("normals" + in + " --out " + np, nullptr, &err) == 0);
  REQUIRE(run_cli("normals" + in + " --output-space ras --out " + nr, nullptr, &err) == 0);
  const Eigen::MatrixX3d n_vox = read_normals(nv), n_lps = read_normals(np), n_ras = read_normals(nr);
  CHECK(max_difference(n_lps, n_vox * seg.geometry.direction.transpose()) < 1e-12);
  CHECK(max_difference(n_ras, n_lps * Eigen::Vector3d(-1, -1, 1).asDiagonal()) == 0.0);

  // solve: the heat step's X is a Laplacian (1 / length^2); Poisson's b from a file is read in the
  // output units, so that b / mm^2 in millimetres gives the g of b in voxels.
  const std::string xv = scratch("xv.txt"), xp = scratch("xp.txt");
  const std::string solve = "solve" + in + " --method fem --system heat --rhs x2 --out ";
  REQUIRE(run_cli(solve + xv + " --output-units voxels", nullptr, &err) == 0);
  REQUIRE(run_cli(solve + xp, nullptr, &err) == 0);
  const Eigen::VectorXd x_vox = read_scalars(xv), x_mm = read_scalars(xp);
  CHECK(read_text(xp).rfind("# X: the heat step's Laplacian in 1/length^2 of physical units (SPACE=LPS)\n", 0) == 0);
  CHECK(max_difference(x_mm, x_vox / (mm * mm)) < 1e-9 * x_vox.cwiseAbs().maxCoeff() / (mm * mm));
  std::string json;
  REQUIRE(run_cli(solve + xp + " --json", &json, &err) == 0);
  CHECK(nlohmann::json::parse(json)["output_units"] == "physical");
  const Eigen::VectorXd b = x_vox.array() - x_vox.mean();  // sums to zero: a compatible Neumann right-hand side
  write_scalars(scratch("b_vox.txt"), b);
  write_scalars(scratch("b_mm.txt"), b / (mm * mm));
  const std::string gv = scratch("gv.txt"), gp = scratch("gp.txt");
  const std::string poisson = "solve" + in + " --method fem --rhs ";
  REQUIRE(run_cli(poisson + scratch("b_vox.txt") + " --output-units voxels --out " + gv, nullptr, &err) == 0);
  REQUIRE(run_cli(poisson + scratch("b_mm.txt") + " --out " + gp, nullptr, &err) == 0);
  const Eigen::VectorXd g_vox = read_scalars(gv), g_mm = read_scalars(gp);
  CHECK(max_difference(g_mm, g_vox) < 1e-8 * g_vox.cwiseAbs().maxCoeff());

  // eigs: -lambda in 1 / length^2.
  std::string out_vox, out_mm, out_world;
  const std::string eigs = "eigs" + in + " --method fem -k 6";
  REQUIRE(run_cli(eigs + " --output-units voxels", &out_vox, &err) == 0);
  REQUIRE(run_cli(eigs, &out_mm, &err) == 0);
  CHECK(err.find("values in 1/length^2 of physical units") != std::string::npos);
  REQUIRE(run_cli(eigs + " --output-units world", &out_world, &err) == 0);
  const std::vector<double> ev = numbers(out_vox), ep = numbers(out_mm), ew = numbers(out_world);
  REQUIRE(ev.size() == 6);
  REQUIRE(ep.size() == 6);
  REQUIRE(ew.size() == 6);
  const double h = 2.0 / 14.0;  // world units: the longest side (14 voxels) spans 2
  for (std::size_t i = 1; i < 6; ++i) {
    CHECK(ep[i] == doctest::Approx(ev[i] / (mm * mm)).epsilon(1e-9));
    CHECK(ew[i] == doctest::Approx(ev[i] / (h * h)).epsilon(1e-9));
  }
  CHECK(run_cli(eigs + " --output-space ras", nullptr, &err) != 0);  // no positions, no space flag
  const std::string ef = scratch("eigs_mm.txt");
  REQUIRE(run_cli(eigs + " --out " + ef, nullptr, &err) == 0);
  CHECK(read_text(ef).rfind("# eigenvalues mu of -L u = mu M u, ascending in 1/length^2 of physical units", 0) == 0);
  const Eigen::VectorXd written = read_scalars(ef);
  REQUIRE(written.size() == 6);
  for (Eigen::Index i = 1; i < 6; ++i) CHECK(written[i] == doctest::Approx(ep[std::size_t(i)]).epsilon(1e-12));
}

#endif
