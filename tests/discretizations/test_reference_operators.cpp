// Acceptance: fem, interpolated, polydec and projected-polydec equal the reference
// implementation's matrices on sphere1, h = 0.2, entry by entry to 1e-12 relative, same sparsity.
#include <doctest/doctest.h>

#include <corrlap/core/config.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/io/text_io.hpp>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

namespace {
void check_against_reference(const std::string& method, const std::string& prefix) {
  const ReferenceCase& rc = reference_case();
  const Operators ops = make_discretization(method)->assemble(rc.mesh, rc.normals, Config{});
  CHECK(ops.warnings.empty());
  const Eigen::SparseMatrix<double> L = read_matrix_market(sphere_ref(prefix + "_L0.mtx"));
  const Eigen::SparseMatrix<double> M = read_matrix_market(sphere_ref(prefix + "_M0.mtx"));
  const MatrixDiff dL = compare_matrices(ops.L, L), dM = compare_matrices(ops.M, M);
  INFO(method << ": L rel " << dL.relative << " pattern " << dL.pattern_mismatch << "; M rel " << dM.relative
              << " pattern " << dM.pattern_mismatch);
  CHECK(dL.relative <= 1e-12);
  CHECK(dL.pattern_mismatch == 0);
  CHECK(dM.relative <= 1e-12);
  CHECK(dM.pattern_mismatch == 0);
}
}  // namespace

TEST_CASE("fem equals the reference NormalCorrectedFEM matrices on sphere1 h=0.2") {
  check_against_reference("fem", "fem");
}
TEST_CASE("interpolated equals the reference InterpolatedCorrectedCalculus L0/M0 on sphere1 h=0.2") {
  check_against_reference("interpolated", "icc");
}
TEST_CASE("polydec equals the reference PolygonalCalculus L0/M0 on sphere1 h=0.2") {
  check_against_reference("polydec", "poly");
}
TEST_CASE("projected-polydec equals the reference projected PolygonalCalculus on sphere1 h=0.2") {
  check_against_reference("projected-polydec", "polyproj");
}
