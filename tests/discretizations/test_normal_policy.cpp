// prepare_normals (discretizations/normal_policy.hpp): validation, orientation policy, and no
// copy of the caller's normals unless they change; Discretization::assemble_into (output reuse).
#include <doctest/doctest.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>

#include "discretizations/test_vrm_support.hpp"

using namespace corrlap;

namespace {
// The normal-policy parameters of `config`, read as a method reads them (config must outlive the call).
ParameterValues policy(const Config& config) { return normal_policy_parameters().read(config, "test"); }
}  // namespace

TEST_CASE("prepare_normals borrows valid normals and copies only when it changes them") {
  const SurfelMesh mesh = test::sphere1_surface(0.25);
  NormalFields nf;
  nf.face = true_face_normals(make_implicit_shape("sphere1"), mesh);
  Operators ops;  // receives warnings and contract_risk
  const std::vector<std::string>& warnings = ops.warnings;
  OrientationReport report;

  const PreparedNormals plain = prepare_normals(mesh, nf, NormalKind::Face, policy(Config()), "test", ops, &report);
  CHECK_FALSE(plain.is_copy());
  CHECK(&plain.matrix() == &nf.face);
  CHECK(report.inconsistent == 0);
  CHECK(warnings.empty());

  // normalize: a rescaled copy; the caller's field is left as it was
  NormalFields scaled = nf;
  scaled.face *= 2.0;
  const PreparedNormals normalized =
      prepare_normals(mesh, scaled, NormalKind::Face, policy(Config::from_key_values({"normalize=true"})), "test", ops);
  CHECK(normalized.is_copy());
  CHECK((normalized.matrix() - nf.face).cwiseAbs().maxCoeff() < 1e-15);
  CHECK(scaled.face.row(0).norm() == doctest::Approx(2.0));
  CHECK_THROWS_WITH_AS(prepare_normals(mesh, scaled, NormalKind::Face, policy(Config()), "test", ops),
                       doctest::Contains("length"), InputError);

  CHECK(ops.contract_risk.empty());

  // one face tangent to its surfel: warn borrows (exact reference values) and says what that
  // breaks; clamp (the default) copies and keeps the contract
  NormalFields tangent = nf;
  const Eigen::Vector3d n0 = trivial_face_normals(mesh).row(0).transpose();
  tangent.face.row(0) = n0.unitOrthogonal().transpose();
  ops.warnings.clear();
  const PreparedNormals warned = prepare_normals(
      mesh, tangent, NormalKind::Face, policy(Config::from_key_values({"orientation=warn"})), "test", ops, &report);
  CHECK_FALSE(warned.is_copy());
  CHECK(report.inconsistent == 1);
  CHECK(report.worst_face == 0);
  REQUIRE(warnings.size() == 1);
  CHECK(warnings[0].find("L may not be negative semi-definite nor M positive definite") != std::string::npos);
  CHECK(warnings[0].find("orientation=clamp") != std::string::npos);
  CHECK(ops.contract_risk.find("1 of") != std::string::npos);
  Operators clamped_ops;
  const PreparedNormals clamped =
      prepare_normals(mesh, tangent, NormalKind::Face, policy(Config()), "test", clamped_ops);
  CHECK(clamped_ops.contract_risk.empty());
  REQUIRE(clamped_ops.warnings.size() == 1);
  CHECK(clamped_ops.warnings[0].find("raised to u.n >= 0.05") != std::string::npos);
  CHECK(clamped.is_copy());
  CHECK(clamped.matrix().row(0).dot(n0) >= 0.05 - 1e-12);
  CHECK(clamped.matrix().row(0).norm() == doctest::Approx(1.0));
  CHECK(tangent.face.row(0).dot(n0) == doctest::Approx(0.0));  // caller's field untouched
  CHECK((clamped.matrix().bottomRows(mesh.num_faces() - 1) - nf.face.bottomRows(mesh.num_faces() - 1)).norm() == 0.0);
}

TEST_CASE("assemble_into reuses the output storage and gives the same bits as assemble") {
  const SurfelMesh mesh = test::sphere1_surface(0.1);
  NormalFields nf;
  const ImplicitShape shape = make_implicit_shape("sphere1");
  nf.face = true_face_normals(shape, mesh);
  nf.vertex = true_vertex_normals(shape, mesh);
  const auto same = [](const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
    return a.rows() == b.rows() && a.nonZeros() == b.nonZeros() &&
           std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
           std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr()) &&
           std::equal(a.valuePtr(), a.valuePtr() + a.nonZeros(), b.valuePtr());
  };
  for (const std::string method :
       {"fem", "polydec", "projected-polydec", "interpolated", "vrm", "corrected-vrm", "heat-kernel"}) {
    CAPTURE(method);
    const auto d = make_discretization(method);
    const Operators fresh = d->assemble(mesh, nf, Config());
    Operators reused;
    d->assemble_into(mesh, nf, Config(), reused);
    CHECK(same(fresh.L, reused.L));
    CHECK(same(fresh.M, reused.M));
    const double* L_storage = reused.L.valuePtr();
    // Different normals, same mesh: new values in the same storage (fem), same bits as fresh.
    NormalFields other = nf;
    other.face.row(3) = (other.face.row(3) + Eigen::RowVector3d(0.05, 0, 0)).normalized();
    other.vertex.row(3) = (other.vertex.row(3) + Eigen::RowVector3d(0.05, 0, 0)).normalized();
    d->assemble_into(mesh, other, Config(), reused);
    const Operators fresh_other = d->assemble(mesh, other, Config());
    CHECK(same(fresh_other.L, reused.L));
    CHECK(same(fresh_other.M, reused.M));
    if (method != "heat-kernel") CHECK(reused.L.valuePtr() == L_storage);  // refilled, no reallocation
  }
  // extras and warnings do not leak from one call to the next
  const auto fem = make_discretization("fem");
  Operators ops;
  fem->assemble_into(mesh, nf, Config::from_key_values({"extras=true"}), ops);
  CHECK(ops.D0.has_value());
  fem->assemble_into(mesh, nf, Config(), ops);
  CHECK_FALSE(ops.D0.has_value());
  CHECK_FALSE(ops.M_lumped.has_value());
}
