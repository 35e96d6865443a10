// Property tests of docs/math.md §12.6, run over every method of the registry (methods that cannot run on
// a surfel mesh with face and vertex normals are skipped with a message), thread-count
// independence, and the input-validation paths of the corrected methods.
#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <cstring>

#include "reference_support.hpp"

using namespace corrlap;
using namespace corrlap::test;

namespace {

// Off-centre sphere so that no symmetry hides an error; no surfel data, so transformed copies stay
// self-consistent (trivial normals come from the corner positions).
const SphereCase& base_case() {
  static const SphereCase s = [] {
    SphereCase c = sphere_case(0.5, Eigen::Vector3d(0.11, -0.07, 0.05));
    c.mesh.surfels.clear();
    return c;
  }();
  return s;
}

SphereCase transformed(const SphereCase& s, const Eigen::Matrix3d& A, const Eigen::Vector3d& t) {
  SphereCase r = s;
  r.mesh.positions = (s.mesh.positions * A.transpose()).rowwise() + t.transpose();
  const double det = A.determinant();
  const double scale = std::cbrt(std::abs(det));
  r.mesh.h = s.mesh.h * scale;
  const Eigen::Matrix3d rot = A / scale;
  r.normals.face = s.normals.face * rot.transpose();
  r.normals.vertex = s.normals.vertex * rot.transpose();
  return r;
}

// Methods that accept the base case; the others are reported and skipped.
std::vector<std::string> runnable_methods() {
  std::vector<std::string> names;
  for (const auto& name : discretization_registry().names()) {
    try {
      make_discretization(name)->assemble(base_case().mesh, base_case().normals, Config{});
      names.push_back(name);
    } catch (const Error& e) {
      MESSAGE("skipping " << name << " in the property tests: " << e.what());
    }
  }
  return names;
}

bool bitwise_equal(const Eigen::SparseMatrix<double>& A, const Eigen::SparseMatrix<double>& B) {
  return A.rows() == B.rows() && A.cols() == B.cols() && A.nonZeros() == B.nonZeros() &&
         std::memcmp(A.valuePtr(), B.valuePtr(), sizeof(double) * std::size_t(A.nonZeros())) == 0 &&
         std::memcmp(A.innerIndexPtr(), B.innerIndexPtr(), sizeof(int) * std::size_t(A.nonZeros())) == 0 &&
         std::memcmp(A.outerIndexPtr(), B.outerIndexPtr(), sizeof(int) * std::size_t(A.outerSize() + 1)) == 0;
}

}  // namespace

TEST_CASE("the registry holds the quad methods") {
  for (const std::string name : {"fem", "polydec", "projected-polydec", "interpolated"}) {
    CHECK(discretization_registry().contains(name));
    const auto d = make_discretization(name);
    CHECK(d->name() == name);
  }
}

TEST_CASE("every method: translation, 90 degree rotation and scaling (docs/math.md §12.6)") {
  const SphereCase& s = base_case();
  for (const auto& name : runnable_methods()) {
    INFO(name);
    const auto d = make_discretization(name);
    const Operators ref = d->assemble(s.mesh, s.normals, Config{});
    const Operators tr = d->assemble(transformed(s, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.3, -0.7, 1.1)).mesh,
                                     s.normals, Config{});
    CHECK(relative_difference(tr.L, ref.L) <= 1e-11);
    CHECK(relative_difference(tr.M, ref.M) <= 1e-11);
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(EIGEN_PI / 2, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
      Eigen::Matrix3d Rexact = R.array().round().matrix();  // exact 90 degree rotation
      const SphereCase r = transformed(s, Rexact, Eigen::Vector3d::Zero());
      const Operators ro = d->assemble(r.mesh, r.normals, Config{});
      INFO("rotation about axis " << axis);
      CHECK(relative_difference(ro.L, ref.L) <= 1e-12);
      CHECK(relative_difference(ro.M, ref.M) <= 1e-12);
    }
    if (name.rfind("heat", 0) == 0) continue;  // docs/math.md §6: t is tied to h, scaling is a different operator
    const double sc = 2.5;
    const SphereCase big = transformed(s, sc * Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
    const Operators so = d->assemble(big.mesh, big.normals, Config{});
    CHECK(relative_difference(so.L, ref.L) <= 1e-12);
    CHECK(relative_difference(so.M, Eigen::SparseMatrix<double>(sc * sc * ref.M)) <= 1e-12);
  }
}

TEST_CASE("every method: L 1 = 0, L and M symmetric, L negative semi-definite, M positive definite") {
  const SphereCase& s = base_case();
  for (const auto& name : runnable_methods()) {
    INFO(name);
    const Operators ops = make_discretization(name)->assemble(s.mesh, s.normals, Config{});
    const double sL = max_abs(ops.L), sM = max_abs(ops.M);
    CHECK((ops.L * Eigen::VectorXd::Ones(ops.L.cols())).cwiseAbs().maxCoeff() <= 1e-13 * sL);
    CHECK(max_abs(Eigen::SparseMatrix<double>(ops.L - Eigen::SparseMatrix<double>(ops.L.transpose()))) <= 1e-14 * sL);
    CHECK(max_abs(Eigen::SparseMatrix<double>(ops.M - Eigen::SparseMatrix<double>(ops.M.transpose()))) <= 1e-14 * sM);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eL(Eigen::MatrixXd(ops.L), Eigen::EigenvaluesOnly);
    CHECK(eL.eigenvalues().maxCoeff() <= 1e-13 * sL);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eM(Eigen::MatrixXd(ops.M), Eigen::EigenvaluesOnly);
    CHECK(eM.eigenvalues().minCoeff() > 0.0);
  }
}

TEST_CASE(
    "every method: flipping face orientation and normals together changes nothing, flipping only normals is rejected") {
  const SphereCase& s = base_case();
  SphereCase flipped = s;
  for (int f = 0; f < s.mesh.num_faces(); ++f)
    for (int k = 0; k < 4; ++k) flipped.mesh.faces(f, k) = s.mesh.faces(f, (4 - k) % 4);
  flipped.normals.face = -s.normals.face;
  flipped.normals.vertex = -s.normals.vertex;
  SphereCase only_normals = s;
  only_normals.normals = flipped.normals;
  for (const auto& name : runnable_methods()) {
    INFO(name);
    const auto d = make_discretization(name);
    const Operators ref = d->assemble(s.mesh, s.normals, Config{});
    const Operators fo = d->assemble(flipped.mesh, flipped.normals, Config{});
    CHECK(relative_difference(fo.L, ref.L) <= 1e-12);
    CHECK(relative_difference(fo.M, ref.M) <= 1e-12);
    if (d->required_normals() == NormalKind::None) continue;
    for (const std::string policy : {"error", "warn", "clamp"}) {
      Config c;
      c.set("orientation", policy);
      CHECK_THROWS_AS(d->assemble(only_normals.mesh, only_normals.normals, c), InputError);
    }
  }
}

TEST_CASE("every method: results are bitwise identical for 1, 2 and 8 threads") {
  SphereCase s = sphere_case(0.05, Eigen::Vector3d(0.013, 0.0, -0.02));
  for (const auto& name : runnable_methods()) {
    INFO(name);
    const auto d = make_discretization(name);
    set_thread_count(1);
    const Operators one = d->assemble(s.mesh, s.normals, Config{});
    for (int t : {2, 8}) {
      set_thread_count(t);
      const Operators many = d->assemble(s.mesh, s.normals, Config{});
      INFO(t << " threads");
      CHECK(bitwise_equal(many.L, one.L));
      CHECK(bitwise_equal(many.M, one.M));
    }
  }
  set_thread_count(0);
}

TEST_CASE("corrected methods reject missing, miscounted, NaN, zero and non-unit normals naming the problem") {
  const SphereCase& s = base_case();
  for (const auto& name : runnable_methods()) {
    const auto d = make_discretization(name);
    const NormalKind kind = d->required_normals();
    if (kind == NormalKind::None) continue;
    INFO(name);
    auto with_field = [&](const Eigen::MatrixX3d& field) {
      NormalFields n = s.normals;
      (kind == NormalKind::Face ? n.face : n.vertex) = field;
      return n;
    };
    const Eigen::MatrixX3d good = kind == NormalKind::Face ? s.normals.face : s.normals.vertex;
    CHECK_THROWS_AS(d->assemble(s.mesh, with_field(Eigen::MatrixX3d()), Config{}), InputError);
    CHECK_THROWS_AS(d->assemble(s.mesh, with_field(good.topRows(good.rows() - 1)), Config{}), InputError);
    Eigen::MatrixX3d bad = good;
    bad(3, 1) = std::nan("");
    CHECK_THROWS_AS(d->assemble(s.mesh, with_field(bad), Config{}), InputError);
    bad = good;
    bad.row(3).setZero();
    CHECK_THROWS_AS(d->assemble(s.mesh, with_field(bad), Config{}), InputError);
    bad = good;
    bad.row(3) *= 1.01;
    try {
      d->assemble(s.mesh, with_field(bad), Config{});
      FAIL("non-unit normal accepted");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find("3") != std::string::npos);  // names the row
    }
    Config norm;
    norm.set("normalize", true);
    const Operators a = d->assemble(s.mesh, with_field(bad), norm);
    const Operators b = d->assemble(s.mesh, s.normals, Config{});
    CHECK(relative_difference(a.L, b.L) <= 1e-14);
    Config unknown;
    unknown.set("no_such_key", 1.0);
    CHECK_THROWS_AS(d->assemble(s.mesh, s.normals, unknown), InputError);
  }
}

TEST_CASE("corrected methods: inconsistent orientation follows the policy error | warn | clamp") {
  const SphereCase& s = base_case();
  for (const auto& name : runnable_methods()) {
    const auto d = make_discretization(name);
    const NormalKind kind = d->required_normals();
    if (kind == NormalKind::None) continue;
    INFO(name);
    NormalFields n = s.normals;
    Eigen::MatrixX3d& field = kind == NormalKind::Face ? n.face : n.vertex;
    field.row(5) = -field.row(5);  // one element pointing inward
    Config err, warn, clamp;
    err.set("orientation", std::string("error"));
    warn.set("orientation", std::string("warn"));
    clamp.set("orientation", std::string("clamp"));
    try {
      d->assemble(s.mesh, n, err);
      FAIL("inconsistent normal accepted under policy error");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find("face") != std::string::npos);
    }
    const Operators w = d->assemble(s.mesh, n, warn);
    CHECK(w.warnings.size() == 1);
    CHECK_FALSE(w.contract_risk.empty());  // used as given: the solver-facing caveat is set
    CHECK(std::isfinite(w.L.sum()));
    const Operators c = d->assemble(s.mesh, n, clamp);
    CHECK(c.warnings.size() == 1);
    CHECK(c.contract_risk.empty());
    const Operators dflt = d->assemble(s.mesh, n, Config{});  // clamp is the default
    CHECK(dflt.warnings.size() == 1);
    CHECK(relative_difference(dflt.L, c.L) == 0.0);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eM(Eigen::MatrixXd(c.M), Eigen::EigenvaluesOnly);
    if (name != "interpolated") CHECK(eM.eigenvalues().minCoeff() > 0.0);  // clamped: positive corrected areas
    CHECK((c.L * Eigen::VectorXd::Ones(c.L.cols())).cwiseAbs().maxCoeff() <= 1e-12 * max_abs(c.L));
  }
}

TEST_CASE("interpolated rejects a non-square face naming it, empty meshes are rejected by every quad method") {
  SphereCase s = flat_grid(3, 1.0);
  s.mesh.positions(5, 0) += 0.2;  // vertex 5 is a corner of faces 0, 1, 3, 4
  try {
    make_discretization("interpolated")->assemble(s.mesh, s.normals, Config{});
    FAIL("non-square face accepted");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("face 0") != std::string::npos);
  }
  // fem and polydec handle general planar quads (docs/math.md §4.2 frame, §2.2 polygon formulas).
  CHECK_NOTHROW(make_discretization("fem")->assemble(s.mesh, s.normals, Config{}));
  CHECK_NOTHROW(make_discretization("polydec")->assemble(s.mesh, s.normals, Config{}));
  SurfelMesh empty;
  for (const std::string name : {"fem", "polydec", "projected-polydec", "interpolated"})
    CHECK_THROWS_AS(make_discretization(name)->assemble(empty, NormalFields{}, Config{}), InputError);
}
