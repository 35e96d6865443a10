// A program that embeds corrlap through its CMake package (installed, or the build tree). It
// includes only the umbrella header and touches every library (core, surface, estimators, pipeline,
// discretizations, backends with CHOLMOD, io, problems) so that a static build's link dependencies
// are all exercised.
#include <cmath>
#include <corrlap/corrlap.hpp>
#include <cstdio>
#include <filesystem>

int main() {
  corrlap::DigitizationParams p;
  p.h = 0.25;
  const corrlap::ImplicitShape shape = corrlap::make_implicit_shape("sphere1");
  const auto grid = corrlap::digitize(shape, p);
  const auto mesh = corrlap::extract_surface(grid);
  const auto info = corrlap::compute_mesh_info(mesh);
  std::printf("V=%d F=%d E=%d\n", info.vertices, info.faces, info.edges);
  // docs/math.md §12.1: sphere1 at h = 0.25 has V = 296, F = 294, E = 588
  if (!(info.vertices == 296 && info.faces == 294 && info.edges == 588)) return 1;

  // pipeline: the same surface through load_surface, and its checks.
  corrlap::ImplicitShapeInput input;
  input.shape = "sphere1";
  input.digitization = p;
  const corrlap::LoadedSurface loaded = corrlap::load_surface(input);
  if (!(loaded.mesh.faces == mesh.faces && corrlap::boundary_condition(loaded.mesh).closed())) return 5;

  // Corrected FEM with true normals, then (M - L) x = M 1 with CHOLMOD: L 1 = 0, so x = 1.
  corrlap::NormalFields normals;
  normals.face = corrlap::true_face_normals(shape, mesh);
  const corrlap::Operators ops = corrlap::make_discretization("fem")->assemble(mesh, normals, corrlap::Config{});
  const Eigen::SparseMatrix<double> A = ops.M - ops.L;
  corrlap::Config solver;
  solver.set("solver", std::string("cholmod"));
  auto chol = corrlap::make_linear_solver(solver);
  chol->compute(A);
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(A.rows());
  const Eigen::MatrixXd x = chol->solve(ops.M * ones);
  const double err = (x.col(0) - ones).cwiseAbs().maxCoeff();
  std::printf("solver %s, max |x - 1| = %.2e\n", chol->name().c_str(), err);
  if (!(err < 1e-10)) return 2;

  // io: the volume round trip and a Matrix Market file.
  const auto dir = std::filesystem::temp_directory_path() / "corrlap_consumer";
  std::filesystem::create_directories(dir);
  const corrlap::Volume vol = corrlap::voxels_to_volume(grid);
  corrlap::write_volume((dir / "v.vol").string(), vol);
  const corrlap::Volume back = corrlap::read_volume((dir / "v.vol").string());
  corrlap::write_matrix_market((dir / "M.mtx").string(), ops.M);
  const auto M2 = corrlap::read_matrix_market((dir / "M.mtx").string());
  std::filesystem::remove_all(dir);
  std::printf("volume %s, M.mtx %s, gzip NRRD %s\n", back.values == vol.values ? "same" : "DIFFERENT",
              (M2 - ops.M).norm() == 0.0 ? "same" : "DIFFERENT", corrlap::nrrd_gzip_supported() ? "yes" : "no");
  if (!(back.values == vol.values && (M2 - ops.M).norm() == 0.0)) return 3;

  // problems + the free function: the Poisson problem of docs/math.md §10.4 with f = x^2.
  const corrlap::Operators fem = corrlap::corrected_fem(mesh, normals.face);
  const corrlap::PoissonResult r =
      corrlap::solve_poisson(fem, mesh.positions, corrlap::test_function("x2"), *corrlap::make_linear_solver());
  std::printf("Poisson x2: L_inf %.3g, L2 %.3g\n", r.errors.linf, r.errors.l2);
  return r.errors.l2 < 0.1 ? 0 : 4;
}
