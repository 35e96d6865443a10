// CLI: corrlap backends and corrlap solve (issue 4).
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <corrlap/discretizations/registry.hpp>

#include <unistd.h>

#include "test_support.hpp"

#ifdef CORRLAP_CLI
namespace {
// Like test::run_cli, but with output files unique per process: ctest runs test cases as
// parallel processes, and run_cli's per-process counter makes them share cli_out_1.txt.
int run_cli(const std::string& args, std::string* out, std::string* err) {
  static int counter = 0;
  const std::string stem = corrlap::test::tmp_path("backends_cli_" + std::to_string(getpid()) + "_" + std::to_string(++counter));
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
  std::vector<std::string> names;
  for (const auto& b : j["linear_solvers"]) names.push_back(b["name"]);
  CHECK(names == std::vector<std::string>{"cg", "cholmod", "eigen-ldlt", "eigen-llt"});
  bool has_ordering = false;
  for (const auto& b : j["linear_solvers"])
    if (b["name"] == "cholmod")
      for (const auto& o : b["options"]) has_ordering = has_ordering || o["name"] == "ordering";
  CHECK(has_ordering);
  CHECK(j["eigen_solvers"].size() == 2);
}

TEST_CASE("corrlap solve rejects unknown backend keys and names before assembling") {
  std::string out, err;
  CHECK(run_cli("solve --shape sphere1 --h 0.2 --bbox -2 2 --solver cg orderin=metis", &out, &err) == 1);
  CHECK(err.find("orderin") != std::string::npos);
  CHECK(err.find("preconditioner") != std::string::npos);  // the valid keys are listed
  CHECK(run_cli("solve --shape sphere1 --h 0.2 --solver pardiso", &out, &err) == 1);
  CHECK(err.find("eigen-ldlt") != std::string::npos);
}

TEST_CASE("corrlap solve: FEM Poisson errors of spec 12.5 with every backend and a JSON config") {
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
    for (const char* key : {"solver", "n", "analyze_s", "factorize_s", "solve_s", "iterations", "residual",
                            "error_linf", "error_l2"})
      CHECK(j.contains(key));
    // spec §12.5: FEM, h = 0.2, backward L2 error on x^2 = 0.0204 (3 significant digits).
    CHECK(j["error_l2"].get<double>() == doctest::Approx(0.0204).epsilon(0.005));
    CHECK(j["residual"].get<double>() < 1e-9);
    if (backend.find("cg") != std::string::npos) {
      CHECK(j["solver"] == "cg");
      CHECK(j["iterations"].get<int>() > 0);
    }
  }
}
#endif
