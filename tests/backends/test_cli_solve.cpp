// CLI: corrlap backends and corrlap solve.
#include <doctest/doctest.h>
#include <unistd.h>

#include <corrlap/corrlap.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

#ifdef CORRLAP_CLI
namespace {
// Like test::run_cli, but with output files unique per process: ctest runs test cases as
// parallel processes, and run_cli's per-process counter makes them share cli_out_1.txt.
int run_cli(const std::string& args, std::string* out, std::string* err) {
  static int counter = 0;
  const std::string stem =
      corrlap::test::tmp_path("backends_cli_" + std::to_string(getpid()) + "_" + std::to_string(++counter));
  const std::string cmd = std::string(CORRLAP_CLI) + " " + args + " >" + stem + ".out 2>" + stem + ".err </dev/null";
  const int status = std::system(cmd.c_str());
  *out = corrlap::test::read_text(stem + ".out");
  *err = corrlap::test::read_text(stem + ".err");
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}
}  // namespace

TEST_CASE("corrlap backends lists every backend with its options") {
  std::string out, err;
  REQUIRE(run_cli("backends --json", &out, &err) == 0);
  const auto j = nlohmann::json::parse(out);
  std::vector<std::string> names, eigen_names;
  for (const auto& b : j["linear_solvers"]) names.push_back(b["name"]);
  for (const auto& b : j["eigen_solvers"]) eigen_names.push_back(b["name"]);
    // petsc and slepc only in a build with them (-DCORRLAP_WITH_PETSC=ON).
#if defined(CORRLAP_WITH_PETSC)
  CHECK(names == std::vector<std::string>{"cg", "cholmod", "eigen-ldlt", "eigen-llt", "petsc"});
  CHECK(eigen_names == std::vector<std::string>{"dense", "shift-invert", "slepc"});
#else
  CHECK(names == std::vector<std::string>{"cg", "cholmod", "eigen-ldlt", "eigen-llt"});
  CHECK(eigen_names == std::vector<std::string>{"dense", "shift-invert"});
#endif
  bool has_ordering = false;
  for (const auto& b : j["linear_solvers"])
    if (b["name"] == "cholmod")
      for (const auto& o : b["options"]) has_ordering = has_ordering || o["name"] == "ordering";
  CHECK(has_ordering);
}

TEST_CASE("corrlap solve rejects unknown backend keys and names before assembling") {
  std::string out, err;
  CHECK(run_cli("solve --shape sphere1 --h 0.2 --bbox -2 2 --solver cg orderin=metis", &out, &err) == 1);
  CHECK(err.find("orderin") != std::string::npos);
  CHECK(err.find("preconditioner") != std::string::npos);  // the valid keys are listed
  CHECK(run_cli("solve --shape sphere1 --h 0.2 --solver pardiso", &out, &err) == 1);
  CHECK(err.find("eigen-ldlt") != std::string::npos);
}

TEST_CASE("corrlap solve: FEM Poisson errors of docs/math.md §12.5 with every backend and a JSON config") {
  if (!corrlap::discretization_registry().contains("fem")) {
    std::string out, err;
    CHECK(run_cli("solve --shape sphere1 --h 0.2 --bbox -2 2 --method fem", &out, &err) == 1);
    CHECK(err.find("unknown discretization") != std::string::npos);
    MESSAGE("discretization 'fem' not registered in this build: end-to-end check skipped");
    return;
  }
  const std::string cfg = corrlap::test::tmp_path("cg.json");
  corrlap::test::write_text(cfg, R"({"solver": "cg", "preconditioner": "ichol", "tolerance": 1e-12})");
  for (const std::string& backend :
       std::vector<std::string>{"--solver cholmod", "--solver eigen-ldlt", "--solver eigen-llt", "--config " + cfg}) {
    CAPTURE(backend);
    std::string out, err;
    REQUIRE(run_cli("solve --shape sphere1 --h 0.2 --bbox -2 2 --method fem --normals true --rhs x2 --json " + backend,
                    &out, &err) == 0);
    const auto j = nlohmann::json::parse(out);
    for (const char* key :
         {"solver", "n", "analyze_s", "factorize_s", "solve_s", "iterations", "residual", "error_linf", "error_l2"})
      CHECK(j.contains(key));
    // docs/math.md §12.5: FEM, h = 0.2, backward L2 error on x^2 = 0.0204 (3 significant digits).
    CHECK(j["error_l2"].get<double>() == doctest::Approx(0.0204).epsilon(0.005));
    CHECK(j["residual"].get<double>() < 1e-9);
    if (backend.find("cg") != std::string::npos) {
      CHECK(j["solver"] == "cg");
      CHECK(j["iterations"].get<int>() > 0);
    }
  }
}
TEST_CASE("corrlap solve: --normals gives the library's fields, the same as corrlap operators") {
  using namespace corrlap;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const VoxelGrid grid = digitize(shape, {.h = 0.2, .min_aabb = -1.5, .max_aabb = 1.5});
  const SurfelMesh mesh = extract_surface(grid);
  auto solver = make_linear_solver();
  const std::string base = "solve --shape sphere1 --h 0.2 --bbox -1.5 1.5 --rhs x2 --json";
  auto cli_l2 = [&](const std::string& args, const std::string& kind) {
    std::string out, err;
    REQUIRE(run_cli(base + " " + args, &out, &err) == 0);
    const auto j = nlohmann::json::parse(out);
    CHECK(j["normals"] == kind);
    CHECK(j["solver"] == kDefaultLinearSolver);
    return j["error_l2"].get<double>();
  };
  // Same operator and solver as the library: the errors agree to rounding (1e-12 relative).
  const double fem_ii =
      solve_poisson(corrected_fem(mesh, ii_face_normals(grid, mesh)), mesh.positions, test_function("x2"), *solver)
          .errors.l2;
  CHECK(cli_l2("--method fem --normals ii", "ii") == doctest::Approx(fem_ii).epsilon(1e-12));
  // Vertex normals of --normals true: normalized sum of the true face normals (docs/math.md §1.5), not the
  // exact radial ones (with those the error is docs/math.md §12.5's 0.0185; with these 0.0204).
  const double icc_true = solve_poisson(interpolated(mesh, true_vertex_normals_from_faces(shape, mesh)), mesh.positions,
                                        test_function("x2"), *solver)
                              .errors.l2;
  const double icc_exact =
      solve_poisson(interpolated(mesh, exact_vertex_normals(shape, mesh)), mesh.positions, test_function("x2"), *solver)
          .errors.l2;
  CHECK(cli_l2("--method interpolated --normals true", "true") == doctest::Approx(icc_true).epsilon(1e-12));
  CHECK(std::abs(icc_true - icc_exact) > 0.05 * icc_exact);
  CHECK(cli_l2("--method fem --normals trivial", "trivial") > 5 * fem_ii);  // uncorrected: no convergence
  CHECK(cli_l2("--method polydec", "none") > 5 * fem_ii);
  // A surfel mesh from a file has no shape and no voxels: auto has nothing to use.
  std::string out, err;
  CHECK(run_cli("solve --method fem --mesh " + corrlap::test::reference_dir() + "/sphere1_h0.2/mesh.obj", &out, &err) ==
        1);
  // The library's message, in library terms, with the CLI's flag of the parameter at fault.
  CHECK(
      err.find("fem needs face normals: give face_normals or a normals source (true, ii, trivial) (--face-normals)") !=
      std::string::npos);
  CHECK(run_cli("solve --method fem --shape sphere1 --h 0.2 --rhs x3", &out, &err) == 1);  // neither a name nor a file
  CHECK(err.find("x3") != std::string::npos);
}

TEST_CASE("corrlap solve --system heat factorizes the paper's diffusion matrix M - dt L (docs/math.md §10.3)") {
  using namespace corrlap;
  if (!discretization_registry().contains("fem")) return;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  const VoxelGrid grid = digitize(shape, {.h = 0.2, .min_aabb = -2, .max_aabb = 2});
  const SurfelMesh mesh = extract_surface(grid);
  auto solver = make_linear_solver();
  const Operators fem = corrected_fem(mesh, true_face_normals(shape, mesh));
  const std::string base = "solve --system heat --shape sphere1 --h 0.2 --bbox -2 2 --method fem --normals true --json";
  for (const char* rhs : {"x2", "expx"}) {
    CAPTURE(rhs);
    std::string out, err;
    REQUIRE(run_cli(base + " --rhs " + rhs, &out, &err) == 0);
    const auto j = nlohmann::json::parse(out);
    CHECK(j["system"] == "heat");
    CHECK(j["dt"].get<double>() == doctest::Approx(0.035 * 0.2).epsilon(1e-14));  // the default factor
    // The library's forward evaluation with the same operator and dt: equal up to rounding.
    const ErrorNorms lib = forward_error(fem, mesh.positions, test_function(rhs), *solver, 0.035 * 0.2);
    CHECK(j["error_linf"].get<double>() == doctest::Approx(lib.linf).epsilon(1e-12));
    CHECK(j["error_l2"].get<double>() == doctest::Approx(lib.l2).epsilon(1e-12));
    CHECK(j["residual"].get<double>() < 1e-12);
  }
  // docs/math.md §12.5: FEM, h = 0.2, diffused forward L_inf on e^x = 0.584 (3 significant digits).
  std::string out, err;
  REQUIRE(run_cli(base + " --rhs expx", &out, &err) == 0);
  CHECK(nlohmann::json::parse(out)["error_linf"].get<double>() == doctest::Approx(0.584).epsilon(0.005));
  // Another factor changes dt (and the error); the Poisson system has no time step.
  REQUIRE(run_cli(base + " --rhs x2 --dt-factor 0.1", &out, &err) == 0);
  CHECK(nlohmann::json::parse(out)["dt"].get<double>() == doctest::Approx(0.02).epsilon(1e-14));
  CHECK(run_cli("solve --system poisson --dt-factor 0.1 --shape sphere1 --h 0.2 --method fem --normals true", &out,
                &err) == 1);
  CHECK(err.find("--dt-factor applies to --system heat only") != std::string::npos);
  CHECK(run_cli("solve --system wave --shape sphere1 --h 0.2", &out, &err) != 0);
  CHECK(err.find("wave") != std::string::npos);
}

TEST_CASE("corrlap solve and eigs say which boundary condition an open surface gets") {
  // {z <= 0} in the box [-1, 1]^3: the surface stops at the box, so it has boundary edges.
  const std::string open = " --method fem --polynomial z --h 0.25 --bbox -1 1 --normals true";
  std::string out, err;
  REQUIRE(run_cli("solve" + open + " --rhs x2 --json", &out, &err) == 0);
  CHECK(err.find("the surface is open (76 boundary edges): natural (zero Neumann) boundary conditions") !=
        std::string::npos);
  CHECK(nlohmann::json::parse(out)["boundary"] == "natural (zero Neumann) on 76 boundary edges");
  REQUIRE(run_cli("eigs" + open + " -k 2", &out, &err) == 0);
  CHECK(err.find("natural (zero Neumann) boundary conditions") != std::string::npos);
  // A closed surface: no note, "closed" in the report.
  REQUIRE(run_cli("solve --method fem --shape sphere1 --h 0.25 --bbox -1.5 1.5 --normals true --rhs x2 --json", &out,
                  &err) == 0);
  CHECK(err.find("open") == std::string::npos);
  CHECK(nlohmann::json::parse(out)["boundary"] == "closed");
}
#endif
