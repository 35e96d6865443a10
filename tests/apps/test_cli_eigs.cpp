// `corrlap eigs` with a sparse shift-invert backend reproduces docs/math.md §12.3 and the dense solver.
#include <doctest/doctest.h>

#include <sstream>
#include <vector>

#include "test_support.hpp"

namespace {
std::vector<double> parse_values(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  return v;
}
}  // namespace

TEST_CASE("eigs with cholmod shift-invert reproduces the FEM spectrum of docs/math.md §12.3 (h = 0.1)") {
  std::string out, err;
  const int rc = corrlap::test::run_cli(
      "eigs --method fem --shape sphere1 --h 0.1 --bbox -2 2 --normals true -k 10 --solver cholmod", &out, &err);
  INFO(err);
  REQUIRE(rc == 0);
  const std::vector<double> v = parse_values(out);
  REQUIRE(v.size() == 10);
  CHECK(std::abs(v[0]) < 1e-8);
  // docs/math.md §12.3 prints 4-6 significant digits: compare at that precision.
  for (int i = 1; i <= 3; ++i) CHECK(v[std::size_t(i)] == doctest::Approx(2.0177).epsilon(5e-5));
  for (int i = 4; i <= 6; ++i) CHECK(v[std::size_t(i)] == doctest::Approx(6.04467).epsilon(5e-6));
  for (int i = 7; i <= 8; ++i) CHECK(v[std::size_t(i)] == doctest::Approx(6.09828).epsilon(5e-6));
  CHECK(v[9] == doctest::Approx(12.0573).epsilon(5e-6));
}

TEST_CASE("eigs sparse and dense paths agree") {
  std::string sparse, dense, err;
  const std::string base = "eigs --method interpolated --shape sphere1 --h 0.2 --bbox -2 2 --normals true -k 12";
  REQUIRE(corrlap::test::run_cli(base + " --solver eigen-ldlt", &sparse, &err) == 0);
  CHECK(err.find("shift-invert (eigen-ldlt,") != std::string::npos);
  REQUIRE(corrlap::test::run_cli(base + " --solver-option dense_threshold=100000", &dense, &err) == 0);
  CHECK(err.find("the dense solver") != std::string::npos);
  const auto a = parse_values(sparse), b = parse_values(dense);
  REQUIRE(a.size() == 12);
  REQUIRE(b.size() == 12);
  for (std::size_t i = 1; i < a.size(); ++i) CHECK(a[i] == doctest::Approx(b[i]).epsilon(1e-8));
  // By default the path is chosen by cost: dense for a tiny problem, Lanczos once n exceeds twice
  // its basis (k = 12: basis 38, so n = 440 is Lanczos; a fixed size threshold would take the dense
  // path far past the crossing, docs/backends.md "Dense or Lanczos").
  REQUIRE(corrlap::test::run_cli(base, &dense, &err) == 0);
  CHECK(err.find("shift-invert (cholmod,") != std::string::npos);
  REQUIRE(corrlap::test::run_cli("eigs --method fem --shape sphere1 --h 0.6 --bbox -2 2 --normals true -k 12", &dense,
                                 &err) == 0);
  CHECK(err.find("the dense solver") != std::string::npos);
  CHECK(corrlap::test::run_cli(base + " --solver nosuchsolver", nullptr, &err) == 1);
  CHECK(err.find("cholmod") != std::string::npos);  // the error lists the valid names
}
